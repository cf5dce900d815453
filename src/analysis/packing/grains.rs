//! Grains as whole bodies: particles grouped by grain id and unwrapped
//! across periodic faces, with their centres and extents.

use crate::engine::SimBox;
use crate::kernels::{Separation, Unwrapped};

/// The particles of each grain, unwrapped so that each grain is whole.
#[derive(Clone, Debug)]
pub struct Grains {
    /// Particle indices of grain `g` (grain ids `0..count`, in order).
    pub members: Vec<Vec<usize>>,
    /// Unwrapped positions of the members of each grain, in `members` order.
    pub positions: Vec<Vec<[f64; 3]>>,
    /// Centre (mean position, unit masses) of each grain, unwrapped.
    pub centres: Vec<[f64; 3]>,
    /// Largest distance from each grain's centre to one of its particles.
    pub extents: Vec<f64>,
}

/// Why grains could not be formed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GrainsError {
    /// Arrays of different lengths.
    #[error("{what}: {got} entries for {expected} particles")]
    Length {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The particle count.
        expected: usize,
    },
    /// A grain id with no particle, or a bond index out of range.
    #[error("{0}")]
    Invalid(String),
}

impl Grains {
    /// Groups particles by `grain` and makes each grain whole: starting
    /// from its lowest-indexed particle, every particle is placed at the
    /// minimum image of a bonded neighbour already placed (breadth first
    /// through `bonds`), so a grain is whole whatever its size relative to
    /// the box; particles no bond reaches are placed at the minimum image
    /// of the grain's first particle. `x` may be wrapped or not.
    pub fn from_bonds(
        simbox: &SimBox,
        x: &[[f64; 3]],
        grain: &[u32],
        bonds: &[[usize; 2]],
    ) -> Result<Self, GrainsError> {
        let n = x.len();
        if grain.len() != n {
            return Err(GrainsError::Length {
                what: "grain ids",
                got: grain.len(),
                expected: n,
            });
        }
        let count = grain.iter().map(|&g| g as usize + 1).max().unwrap_or(0);
        let mut members = vec![Vec::new(); count];
        for (i, &g) in grain.iter().enumerate() {
            members[g as usize].push(i);
        }
        if let Some(g) = members.iter().position(Vec::is_empty) {
            return Err(GrainsError::Invalid(format!(
                "grain {g} has no particle (grain ids must run 0..{count} without gaps)"
            )));
        }
        let mut offsets = vec![0usize; n + 1];
        for &[i, j] in bonds {
            if i >= n || j >= n {
                return Err(GrainsError::Invalid(format!(
                    "bond ({i}, {j}) names a particle beyond the {n} given"
                )));
            }
            offsets[i + 1] += 1;
            offsets[j + 1] += 1;
        }
        for k in 0..n {
            offsets[k + 1] += offsets[k];
        }
        let mut partners = vec![0usize; offsets[n]];
        let mut cursor = offsets.clone();
        for &[i, j] in bonds {
            partners[cursor[i]] = j;
            cursor[i] += 1;
            partners[cursor[j]] = i;
            cursor[j] += 1;
        }
        let image = simbox.minimum_image();
        let mut unwrapped: Vec<Option<[f64; 3]>> = vec![None; n];
        let mut queue = std::collections::VecDeque::new();
        for m in &members {
            let first = m[0];
            for &start in m {
                if unwrapped[start].is_some() {
                    continue;
                }
                // A new bonded cluster: anchor it near the grain's first particle.
                let anchor = unwrapped[first].unwrap_or(x[first]);
                let d = image.delta(&x[start], &anchor);
                unwrapped[start] = Some([anchor[0] + d[0], anchor[1] + d[1], anchor[2] + d[2]]);
                queue.push_back(start);
                while let Some(i) = queue.pop_front() {
                    let xi = unwrapped[i].expect("placed before queued");
                    for &j in &partners[offsets[i]..offsets[i + 1]] {
                        if unwrapped[j].is_none() && grain[j] == grain[i] {
                            let d = image.delta(&x[j], &xi);
                            unwrapped[j] = Some([xi[0] + d[0], xi[1] + d[1], xi[2] + d[2]]);
                            queue.push_back(j);
                        }
                    }
                }
            }
        }
        let positions: Vec<Vec<[f64; 3]>> = members
            .iter()
            .map(|m| {
                m.iter()
                    .map(|&i| unwrapped[i].expect("every particle placed"))
                    .collect()
            })
            .collect();
        let centres: Vec<[f64; 3]> = positions.iter().map(|p| mean(p)).collect();
        let extents = positions
            .iter()
            .zip(&centres)
            .map(|(p, c)| {
                p.iter()
                    .map(|x| Unwrapped.distance(x, c))
                    .fold(0.0, f64::max)
            })
            .collect();
        Ok(Self {
            members,
            positions,
            centres,
            extents,
        })
    }

    /// Number of grains.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Whether there is no grain.
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }
}

/// The mean of `points`.
pub fn mean(points: &[[f64; 3]]) -> [f64; 3] {
    let n = points.len().max(1) as f64;
    [0, 1, 2].map(|k| points.iter().map(|p| p[k]).sum::<f64>() / n)
}
