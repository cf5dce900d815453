//! Contacts between grains and the coordination number without rattlers.

use crate::engine::pairs_within;
use crate::engine::SimBox;
use crate::kernels::Separation;

/// Grain pairs `(a, b)`, `a < b`, with at least one particle of `a` closer
/// than `contact` to one of `b` (the pair force's range): grains that
/// exert force on each other. `x` may be wrapped or not.
pub fn force_contacts(
    simbox: &SimBox,
    x: &[[f64; 3]],
    grain: &[u32],
    contact: f64,
) -> Vec<[usize; 2]> {
    let mut pairs: Vec<[usize; 2]> = pairs_within(simbox, x, contact)
        .into_iter()
        .filter_map(|(i, j, _)| {
            let (a, b) = (grain[i] as usize, grain[j] as usize);
            (a != b).then_some([a.min(b), a.max(b)])
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Grain pairs whose centres are closer than `cutoff` in any periodic
/// image (a pair counts once), so a cutoff beyond half the box, as in a
/// small packing compressed far, misses no contact. All pairs are tried:
/// fine for the thousands of grains a packing has.
pub fn geometric_contacts(simbox: &SimBox, centres: &[[f64; 3]], cutoff: f64) -> Vec<[usize; 2]> {
    let faces = simbox.face_distances();
    let reach = [0, 1, 2].map(|d| {
        if simbox.periodic[d] {
            (cutoff / faces[d]).ceil() as i32 + 1
        } else {
            0
        }
    });
    let image = simbox.minimum_image();
    let cut2 = cutoff * cutoff;
    let mut pairs = Vec::new();
    for i in 0..centres.len() {
        for j in i + 1..centres.len() {
            let base = image.delta(&centres[j], &centres[i]);
            let mut touching = false;
            'images: for a in -reach[0]..=reach[0] {
                for b in -reach[1]..=reach[1] {
                    for c in -reach[2]..=reach[2] {
                        let shift = simbox.image_vector(&[a, b, c]);
                        let d = [0, 1, 2].map(|k| base[k] + shift[k]);
                        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < cut2 {
                            touching = true;
                            break 'images;
                        }
                    }
                }
            }
            if touching {
                pairs.push([i, j]);
            }
        }
    }
    pairs
}

/// The mean coordination number of a contact network once rattlers are
/// gone.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Coordination {
    /// Mean contacts per grain among the grains that are not rattlers,
    /// counting only contacts between such grains; 0 when none is left.
    pub z: f64,
    /// Grains removed as rattlers.
    pub rattlers: usize,
    /// Grains left.
    pub grains: usize,
}

/// Removes rattlers, grains with at most `max_rattler_contacts` contacts,
/// repeatedly (removing one can make a neighbour a rattler) until none is
/// left, and returns the mean coordination number of the rest. The paper
/// excludes grains with two or fewer contacts.
pub fn coordination(
    grains: usize,
    pairs: &[[usize; 2]],
    max_rattler_contacts: usize,
) -> Coordination {
    let mut degree = vec![0usize; grains];
    let mut partners = vec![Vec::new(); grains];
    for &[a, b] in pairs {
        degree[a] += 1;
        degree[b] += 1;
        partners[a].push(b);
        partners[b].push(a);
    }
    let mut removed = vec![false; grains];
    let mut stack: Vec<usize> = (0..grains)
        .filter(|&g| degree[g] <= max_rattler_contacts)
        .collect();
    while let Some(g) = stack.pop() {
        if removed[g] {
            continue;
        }
        removed[g] = true;
        for &h in &partners[g] {
            if !removed[h] {
                degree[h] -= 1;
                if degree[h] <= max_rattler_contacts {
                    stack.push(h);
                }
            }
        }
    }
    let left = removed.iter().filter(|r| !**r).count();
    let contacts: usize = (0..grains)
        .filter(|&g| !removed[g])
        .map(|g| degree[g])
        .sum();
    Coordination {
        z: if left > 0 {
            contacts as f64 / left as f64
        } else {
            0.0
        },
        rattlers: grains - left,
        grains: left,
    }
}
