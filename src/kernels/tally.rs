//! Which atoms receive a force, and how energy and virial are counted.

/// Which atoms are owned by the caller, in LAMMPS's sense.
///
/// Atoms `0..n_owned` are owned; higher indices are ghosts. With `newton`
/// on, an interaction is computed once and its force is applied to both atoms
/// (ghost forces are summed back to their owners by the caller). With it off,
/// each rank computes the interaction and applies force only to atoms it
/// owns, and energy and virial are split half and half, exactly as LAMMPS's
/// `ev_tally` does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ownership {
    /// Number of owned atoms; indices at or above this are ghosts.
    pub n_owned: usize,
    /// Whether forces on ghost atoms are applied (and later communicated).
    pub newton: bool,
}

impl Ownership {
    /// Every atom is owned: the native engine's case.
    pub fn all(n: usize) -> Self {
        Self {
            n_owned: n,
            newton: true,
        }
    }

    /// `(apply to i, apply to j, fraction of energy and virial to tally)`.
    #[inline(always)]
    pub(crate) fn split(&self, i: usize, j: usize) -> (bool, bool, f64) {
        if self.newton {
            (true, true, 1.0)
        } else {
            let oi = i < self.n_owned;
            let oj = j < self.n_owned;
            (oi, oj, 0.5 * (oi as u8 + oj as u8) as f64)
        }
    }
}

/// Energy and virial summed over a list of interactions.
///
/// The virial is `sum r_ij,a F_ij,b` in LAMMPS's order
/// `[xx, yy, zz, xy, xz, yz]`; divide by the volume for the pressure tensor.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tally {
    /// Potential energy (for bonds, the spring proxy `k (r - r0)^2 / 2`).
    pub energy: f64,
    /// Virial tensor `[xx, yy, zz, xy, xz, yz]`.
    pub virial: [f64; 6],
}

impl Tally {
    #[inline(always)]
    pub(crate) fn add(&mut self, fraction: f64, energy: f64, del: &[f64; 3], fpair: f64) {
        let s = fraction * fpair;
        self.energy += fraction * energy;
        self.virial[0] += s * del[0] * del[0];
        self.virial[1] += s * del[1] * del[1];
        self.virial[2] += s * del[2] * del[2];
        self.virial[3] += s * del[0] * del[1];
        self.virial[4] += s * del[0] * del[2];
        self.virial[5] += s * del[1] * del[2];
    }

    /// Adds the virial of a force `force` on `i` (and its opposite on `j`)
    /// that need not be along `del`, as LAMMPS's `ev_tally_xyz` does: the
    /// off-diagonal entries are `del_a force_b` with `a < b`.
    #[inline(always)]
    pub(crate) fn add_vector(&mut self, fraction: f64, del: &[f64; 3], force: &[f64; 3]) {
        self.virial[0] += fraction * del[0] * force[0];
        self.virial[1] += fraction * del[1] * force[1];
        self.virial[2] += fraction * del[2] * force[2];
        self.virial[3] += fraction * del[0] * force[1];
        self.virial[4] += fraction * del[0] * force[2];
        self.virial[5] += fraction * del[1] * force[2];
    }

    /// Sum of two tallies.
    pub fn merged(mut self, other: &Tally) -> Tally {
        self.energy += other.energy;
        for (a, b) in self.virial.iter_mut().zip(other.virial.iter()) {
            *a += b;
        }
        self
    }
}

/// Per-atom sums (forces, volumes) of the first atom of a run of
/// consecutive list entries, held in registers until the run ends.
///
/// LAMMPS lists a bond under its first atom, so a list is runs of entries
/// that share it. Adding to memory entry by entry chains each addition to
/// the last through a store and a reload; here the run's sum is loaded
/// once and stored once. The additions are the same, in the same order,
/// so the sums are the same bits.
///
/// Every entry must call [`RunningSum::first`] before it writes to any
/// atom, and [`RunningSum::finish`] must follow the last. The first atom's
/// value is loaded and stored back even where the entry does not own it
/// (unchanged, the same bits), so the sums must cover every index.
pub(crate) struct RunningSum<T> {
    atom: usize,
    sum: T,
}

impl<T: Copy + Default> RunningSum<T> {
    const NONE: usize = usize::MAX;

    pub(crate) fn new() -> Self {
        Self {
            atom: Self::NONE,
            sum: T::default(),
        }
    }

    /// The sum of `atom`, the entry's first atom: a new run if it is not
    /// the current one (the current run stored first).
    #[inline(always)]
    pub(crate) fn first<'a>(&'a mut self, atom: usize, out: &mut [T]) -> &'a mut T {
        if atom != self.atom {
            self.finish(out);
            self.atom = atom;
            self.sum = out[atom];
        }
        &mut self.sum
    }

    /// The sum of `atom`, the entry's second atom: the run's if it is the
    /// run's atom (an entry from an atom to itself), memory otherwise.
    #[inline(always)]
    pub(crate) fn second<'a>(&'a mut self, atom: usize, out: &'a mut [T]) -> &'a mut T {
        if atom == self.atom {
            &mut self.sum
        } else {
            &mut out[atom]
        }
    }

    /// Stores the current run's sum.
    #[inline(always)]
    pub(crate) fn finish(&mut self, out: &mut [T]) {
        if self.atom != Self::NONE {
            out[self.atom] = self.sum;
            self.atom = Self::NONE;
        }
    }
}

/// [`apply_pair_force`] with atom `i`'s sum held in `run`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn apply_pair_force_in_run(
    run: &mut RunningSum<[f64; 3]>,
    f: &mut [[f64; 3]],
    i: usize,
    j: usize,
    on_i: bool,
    on_j: bool,
    del: &[f64; 3],
    fpair: f64,
) {
    let fx = del[0] * fpair;
    let fy = del[1] * fpair;
    let fz = del[2] * fpair;
    let fi = run.first(i, f);
    if on_i {
        fi[0] += fx;
        fi[1] += fy;
        fi[2] += fz;
    }
    if on_j {
        let fj = run.second(j, f);
        fj[0] -= fx;
        fj[1] -= fy;
        fj[2] -= fz;
    }
}

/// Adds `fpair * del` to atom `i` and subtracts it from atom `j`, as owned.
#[inline(always)]
pub(crate) fn apply_pair_force(
    f: &mut [[f64; 3]],
    i: usize,
    j: usize,
    on_i: bool,
    on_j: bool,
    del: &[f64; 3],
    fpair: f64,
) {
    let fx = del[0] * fpair;
    let fy = del[1] * fpair;
    let fz = del[2] * fpair;
    if on_i {
        let fi = &mut f[i];
        fi[0] += fx;
        fi[1] += fy;
        fi[2] += fz;
    }
    if on_j {
        let fj = &mut f[j];
        fj[0] -= fx;
        fj[1] -= fy;
        fj[2] -= fz;
    }
}
