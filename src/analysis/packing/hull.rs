//! The convex hull of a grain's particle centres: its volume, surface area
//! and asphericity, and a point-inside test for the Monte Carlo volume
//! fraction. The hull itself comes from `parry3d-f64` (quickhull).

use parry3d_f64::math::Vector;
use parry3d_f64::transformation::try_convex_hull;

/// Why a point set has no usable hull.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum HullError {
    /// Fewer than four points.
    #[error("{0} points cannot span a volume (a hull needs at least 4)")]
    TooFewPoints(usize),
    /// The points lie on a plane or a line (or the hull library failed).
    #[error("the points are degenerate (flat, collinear or not finite): {0}")]
    Degenerate(String),
}

/// A closed convex hull, stored as outward face planes.
#[derive(Clone, Debug)]
pub struct Hull {
    /// Enclosed volume (d^3).
    pub volume: f64,
    /// Surface area (d^2).
    pub area: f64,
    /// Centroid of the hull's vertices, the reference point of `planes`.
    pub centre: [f64; 3],
    /// Largest distance from `centre` to a vertex.
    pub outer_radius: f64,
    /// Smallest distance from `centre` to a face plane: points closer than
    /// this are inside without a plane test.
    pub inner_radius: f64,
    /// Face planes `(unit outward normal n, offset h)`: a point `q` is
    /// inside when `n . (q - centre) <= h` for every face.
    planes: Vec<([f64; 3], f64)>,
}

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl Hull {
    /// The hull of `points` (they should be one grain, unwrapped).
    pub fn of(points: &[[f64; 3]]) -> Result<Self, HullError> {
        if points.len() < 4 {
            return Err(HullError::TooFewPoints(points.len()));
        }
        if !points.iter().flatten().all(|c| c.is_finite()) {
            return Err(HullError::Degenerate("a coordinate is not finite".into()));
        }
        let input: Vec<Vector> = points
            .iter()
            .map(|p| Vector::new(p[0], p[1], p[2]))
            .collect();
        // The library still asserts on some degenerate inputs: a panic
        // there is a degenerate hull here, not the end of the analysis.
        let (vertices, faces) = std::panic::catch_unwind(|| try_convex_hull(&input))
            .map_err(|_| HullError::Degenerate("the hull library gave up on these points".into()))?
            .map_err(|e| HullError::Degenerate(e.to_string()))?;
        let v: Vec<[f64; 3]> = vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
        if v.len() < 4 || faces.len() < 4 {
            return Err(HullError::Degenerate(format!(
                "the hull has {} vertices and {} faces",
                v.len(),
                faces.len()
            )));
        }
        let n = v.len() as f64;
        let centre = [0, 1, 2].map(|k| v.iter().map(|p| p[k]).sum::<f64>() / n);
        let outer_radius = v
            .iter()
            .map(|p| dot(&sub(p, &centre), &sub(p, &centre)).sqrt())
            .fold(0.0, f64::max);
        let mut volume = 0.0;
        let mut area = 0.0;
        let mut planes = Vec::with_capacity(faces.len());
        for f in &faces {
            let [a, b, c] = f.map(|i| sub(&v[i as usize], &centre));
            let mut normal = cross(&sub(&b, &a), &sub(&c, &a));
            let twice_area = dot(&normal, &normal).sqrt();
            area += 0.5 * twice_area;
            // Tetrahedron centre-a-b-c: positive for an outward face, as
            // the centre is inside a convex hull.
            let six_volume = dot(&a, &cross(&b, &c)).abs();
            volume += six_volume / 6.0;
            if twice_area > 0.0 {
                normal = normal.map(|x| x / twice_area);
                let mut h = dot(&normal, &a);
                if h < 0.0 {
                    normal = normal.map(|x| -x);
                    h = -h;
                }
                planes.push((normal, h));
            }
        }
        // A flat or collinear set gives a hull of (near) zero thickness.
        if volume.is_nan() || volume <= 1e-9 * outer_radius.powi(3) {
            return Err(HullError::Degenerate(format!(
                "the hull encloses no volume ({volume:e} d^3 across {outer_radius:e} d)"
            )));
        }
        let inner_radius = planes.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        Ok(Self {
            volume,
            area,
            centre,
            outer_radius,
            inner_radius,
            planes,
        })
    }

    /// Asphericity `A^(3/2) / (6 sqrt(pi) V)`: 1 for a sphere, larger for
    /// any other shape (a cube: `(6^(3/2)) / (6 sqrt(pi))`, about 1.382).
    pub fn asphericity(&self) -> f64 {
        self.area.powf(1.5) / (6.0 * std::f64::consts::PI.sqrt() * self.volume)
    }

    /// Whether the point at offset `r` from [`Hull::centre`] is inside (or
    /// on) the hull.
    #[inline]
    pub fn contains_offset(&self, r: &[f64; 3]) -> bool {
        let r2 = dot(r, r);
        if r2 <= self.inner_radius * self.inner_radius {
            return true;
        }
        if r2 > self.outer_radius * self.outer_radius {
            return false;
        }
        self.planes.iter().all(|(n, h)| dot(n, r) <= *h)
    }
}
