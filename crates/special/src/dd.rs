//! Minimal double-double ("dd") arithmetic, used only where a product or a
//! period must be known beyond `f64` precision (argument reduction of the
//! Jacobi functions).  A value is `hi + lo` with `|lo| <= ulp(hi) / 2`.
//!
//! Error-free transformations (Knuth's two-sum, Dekker's two-product with
//! Veltkamp splitting) are used instead of `mul_add` so that the code is fast
//! on targets compiled without hardware FMA.

/// A double-double number `hi + lo`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Dd {
    pub hi: f64,
    pub lo: f64,
}

/// π as a double-double.
pub(crate) const PI: Dd = Dd {
    hi: std::f64::consts::PI,
    lo: 1.224_646_799_147_353_2e-16,
};

/// `a + b = s + e` exactly.
#[inline]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// `a + b = s + e` exactly, assuming `|a| >= |b|` (or `a == 0`).
#[cfg(test)]
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let e = b - (s - a);
    (s, e)
}

/// Veltkamp split of `a` into two 26-bit halves.
#[inline]
fn split(a: f64) -> (f64, f64) {
    const SPLITTER: f64 = 134_217_729.0; // 2^27 + 1
    let t = SPLITTER * a;
    let hi = t - (t - a);
    (hi, a - hi)
}

/// `a * b = p + e` exactly (for |a|, |b| well below 1e300).
#[inline]
pub(crate) fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, e)
}

/// `a² = p + e` exactly.
#[inline]
pub(crate) fn two_square(a: f64) -> (f64, f64) {
    let p = a * a;
    let (ah, al) = split(a);
    let e = ((ah * ah - p) + 2.0 * ah * al) + al * al;
    (p, e)
}

impl Dd {
    /// Normalise `hi + lo` (any magnitudes) into a double-double.
    #[inline]
    pub(crate) fn new(hi: f64, lo: f64) -> Dd {
        let (hi, lo) = two_sum(hi, lo);
        Dd { hi, lo }
    }

    /// Multiplication by an exact power of two.
    #[inline]
    pub(crate) fn scale(self, two_pow: f64) -> Dd {
        Dd {
            hi: self.hi * two_pow,
            lo: self.lo * two_pow,
        }
    }
}

/// Full double-double arithmetic, only needed by the reference computations
/// in the unit tests.
#[cfg(test)]
impl Dd {
    pub(crate) const ONE: Dd = Dd { hi: 1.0, lo: 0.0 };

    pub(crate) fn add(self, o: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, o.hi);
        let (t, f) = two_sum(self.lo, o.lo);
        let (s, e) = quick_two_sum(s, e + t);
        let (hi, lo) = quick_two_sum(s, e + f);
        Dd { hi, lo }
    }

    pub(crate) fn sub(self, o: Dd) -> Dd {
        self.add(Dd {
            hi: -o.hi,
            lo: -o.lo,
        })
    }

    pub(crate) fn mul(self, o: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, o.hi);
        let e = e + (self.hi * o.lo + self.lo * o.hi);
        let (hi, lo) = quick_two_sum(p, e);
        Dd { hi, lo }
    }

    pub(crate) fn mul_f64(self, b: f64) -> Dd {
        let (p, e) = two_prod(self.hi, b);
        let e = e + self.lo * b;
        let (hi, lo) = quick_two_sum(p, e);
        Dd { hi, lo }
    }

    pub(crate) fn div(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self.sub(o.mul_f64(q1));
        let q2 = r.hi / o.hi;
        let r = r.sub(o.mul_f64(q2));
        let q3 = r.hi / o.hi;
        let (hi, lo) = quick_two_sum(q1, q2);
        Dd { hi, lo }.add(Dd { hi: q3, lo: 0.0 })
    }

    pub(crate) fn div_f64(self, b: f64) -> Dd {
        self.div(Dd { hi: b, lo: 0.0 })
    }

    /// Square root (of a non-negative value).
    pub(crate) fn sqrt(self) -> Dd {
        if self.hi <= 0.0 {
            return Dd { hi: 0.0, lo: 0.0 };
        }
        let s = self.hi.sqrt();
        let (p, e) = two_prod(s, s);
        let corr = (((self.hi - p) - e) + self.lo) / (2.0 * s);
        let (hi, lo) = quick_two_sum(s, corr);
        Dd { hi, lo }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_square_is_exact() {
        for &a in &[
            1.0 + f64::EPSILON,
            0.1,
            3.7e-9,
            1_234.567_890_123,
            1.0 - 1e-12,
        ] {
            assert_eq!(two_square(a), two_prod(a, a));
        }
    }

    #[test]
    fn two_prod_is_exact() {
        let a = 1.0 + f64::EPSILON;
        let (p, e) = two_prod(a, a);
        // (1 + eps)^2 = 1 + 2 eps + eps^2
        assert_eq!(p, 1.0 + 2.0 * f64::EPSILON);
        assert_eq!(e, f64::EPSILON * f64::EPSILON);
    }

    #[test]
    fn sqrt_two_squared() {
        let two = Dd::new(2.0, 0.0);
        let r = two.sqrt();
        let back = r.mul(r).sub(two);
        assert!(back.hi.abs() < 1e-30, "{back:?}");
        let q = Dd::ONE.div(Dd::new(3.0, 0.0)).mul_f64(3.0).sub(Dd::ONE);
        assert!(q.hi.abs() < 1e-31, "{q:?}");
    }
}
