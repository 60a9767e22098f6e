//! Orthographic views of the sphere: the oblique view and the three axis views of the
//! paper's shape figures (Figs. 2, 9, 10).

use nalgebra::Vector3;

/// An orthographic camera: screen axes `right`, `up` and the direction `toward` the viewer
/// (a right-handed orthonormal frame, `right × up = toward`).
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Panel title.
    pub name: String,
    /// Screen x axis (to the right).
    pub right: Vector3<f64>,
    /// Screen y axis (up).
    pub up: Vector3<f64>,
    /// Unit vector from the sphere's centre toward the viewer.
    pub toward: Vector3<f64>,
}

/// A projected point: screen coordinates in units of the data (`u` right, `v` up) and the
/// depth (`> 0` nearer the viewer than the sphere's centre).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Right.
    pub u: f64,
    /// Up.
    pub v: f64,
    /// Toward the viewer.
    pub depth: f64,
}

impl View {
    /// A camera looking at the origin from azimuth `az` and elevation `el` (radians), with
    /// `+z` pointing up on the screen.
    pub fn oblique(name: &str, az: f64, el: f64) -> Self {
        let toward = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        let z = Vector3::z();
        let up = (z - toward * z.dot(&toward)).normalize();
        let right = up.cross(&toward);
        View {
            name: name.into(),
            right,
            up,
            toward,
        }
    }

    /// Looking from `+x`: `y` to the right, `z` up.
    pub fn from_x() -> Self {
        View {
            name: "view from +x (y right, z up)".into(),
            right: Vector3::y(),
            up: Vector3::z(),
            toward: Vector3::x(),
        }
    }

    /// Looking from `+y`: `−x` to the right, `z` up.
    pub fn from_y() -> Self {
        View {
            name: "view from +y (−x right, z up)".into(),
            right: -Vector3::x(),
            up: Vector3::z(),
            toward: Vector3::y(),
        }
    }

    /// Looking from `+z`: `x` to the right, `y` up.
    pub fn from_z() -> Self {
        View {
            name: "view from +z (x right, y up)".into(),
            right: Vector3::x(),
            up: Vector3::y(),
            toward: Vector3::z(),
        }
    }

    /// The paper's four viewpoints: an oblique view (azimuth 35°, elevation 25°) and the
    /// three axis views.
    pub fn paper_set() -> [View; 4] {
        [
            View::oblique(
                "oblique view (azimuth 35°, elevation 25°)",
                35f64.to_radians(),
                25f64.to_radians(),
            ),
            View::from_x(),
            View::from_y(),
            View::from_z(),
        ]
    }

    /// Project a point.
    pub fn project(&self, p: &Vector3<f64>) -> Projected {
        Projected {
            u: p.dot(&self.right),
            v: p.dot(&self.up),
            depth: p.dot(&self.toward),
        }
    }
}
