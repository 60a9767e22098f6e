//! Colour maps and colour arithmetic.
//!
//! The loop's colour map runs dark blue → teal → orange → dark red. Every colour of it is
//! dark enough to read on a white page and on the translucent sphere, which viridis's pale
//! yellow end is not.

/// An RGB colour with components in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rgb(pub f64, pub f64, pub f64);

impl Rgb {
    /// From a `0xRRGGBB` integer.
    pub fn hex(v: u32) -> Self {
        Rgb(
            f64::from((v >> 16) & 0xff) / 255.0,
            f64::from((v >> 8) & 0xff) / 255.0,
            f64::from(v & 0xff) / 255.0,
        )
    }

    /// `#rrggbb`.
    pub fn css(self) -> String {
        let c = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
        format!("#{:02x}{:02x}{:02x}", c(self.0), c(self.1), c(self.2))
    }

    /// Linear mix: `t = 0` gives `self`, `t = 1` gives `other`.
    pub fn mix(self, other: Rgb, t: f64) -> Rgb {
        let t = t.clamp(0.0, 1.0);
        Rgb(
            self.0 + t * (other.0 - self.0),
            self.1 + t * (other.1 - self.1),
            self.2 + t * (other.2 - self.2),
        )
    }
}

/// White.
pub const WHITE: Rgb = Rgb(1.0, 1.0, 1.0);

const MAP: [u32; 7] = [
    0x22_2f_8f, 0x1f_5f_b4, 0x17_8f_9c, 0x4d_a3_4a, 0xd8_8a_10, 0xd0_4a_1c, 0x9e_10_2c,
];

/// The loop colour map at `t ∈ [0, 1]` (clamped).
pub fn colormap(t: f64) -> Rgb {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (MAP.len() - 1) as f64;
    let i = (x.floor() as usize).min(MAP.len() - 2);
    Rgb::hex(MAP[i]).mix(Rgb::hex(MAP[i + 1]), x - i as f64)
}

/// Colours for branches 1, 2, 3, …: blue, red, green, pink (as in the paper's Fig. 3), then
/// more; branch 0 (the circle) grey.
pub fn branch_color(branch: u32) -> &'static str {
    const C: [&str; 8] = [
        "#1f4fd1", "#d62728", "#2ca02c", "#e377c2", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f",
    ];
    if branch == 0 {
        // The circle (branch 0) is not one of the paper's branches: grey, apart from them.
        return "#666666";
    }
    C[(branch as usize - 1) % C.len()]
}

/// Maps data values to `[0, 1]` over a range; a constant column maps to the middle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// Smallest value (the colour bar's bottom).
    pub min: f64,
    /// Largest value (the colour bar's top).
    pub max: f64,
}

impl Scale {
    /// The range of `values` (which must be finite and non-empty).
    pub fn of(values: &[f64]) -> Self {
        let mut min = f64::INFINITY;
        let mut max = f64::NEG_INFINITY;
        for &v in values {
            min = min.min(v);
            max = max.max(v);
        }
        if !min.is_finite() {
            return Scale { min: 0.0, max: 1.0 };
        }
        Scale { min, max }
    }

    /// Position of `v` in the range, in `[0, 1]`.
    pub fn t(&self, v: f64) -> f64 {
        if self.max - self.min <= 1e-12 * (self.max.abs() + self.min.abs()).max(1e-300) {
            0.5
        } else {
            ((v - self.min) / (self.max - self.min)).clamp(0.0, 1.0)
        }
    }
}
