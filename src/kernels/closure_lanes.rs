//! The multi-contact closure's corrections four receivers at a time.
//!
//! [`super::surface_corrections`] forms, for each contact `c` of a sphere,
//! the half-space displacement from every other contact `k` that pressed,
//! one term at a time: a square root and one or two divisions each, in a
//! chain the processor cannot overlap. Here a sphere's contacts are packed as
//! receivers into blocks of four lanes, and each source adds its term to a
//! whole block in one pass of plain per-lane loops, which the compiler
//! turns into vector instructions (two lanes of SSE2 in the portable
//! build, four of AVX2 when the processor has it, chosen at run time).
//!
//! Each lane sums its own receiver's terms in source order, as the
//! one-term loop does, and every term is formed by the function
//! [`HalfSpace::displacement`] forms it with (branch-free, without fused
//! multiply-adds). So the corrections are the same bit for bit on every
//! instruction set.

// Lanes are written `for l in 0..LANES` over several arrays at once, the
// form the compiler turns into vector instructions.
#![allow(clippy::needless_range_loop)]

use super::isa::Isa;
use super::multicontact::{
    Closure, ContactPoint, HalfSpace, MprSwitch, MprTest, COINCIDENT_POINTS,
};

/// Lanes per receiver block.
const LANES: usize = 4;

type Lanes = [f64; LANES];

/// Four receivers of one sphere, component by component, with their
/// contacts' places in the sphere's list.
#[derive(Clone, Copy, Debug, Default)]
struct ReceiverBlock {
    point: [Lanes; 3],
    normal: [Lanes; 3],
    contact: [usize; LANES],
}

/// What a block of receivers has summed.
#[derive(Clone, Copy, Debug)]
struct BlockSums {
    sum: Lanes,
    dropped: [usize; LANES],
}

/// How a receiver takes a term: every term adds up (the standard
/// closure), or terms beyond `limit` are counted instead (the advanced).
#[derive(Clone, Copy, Debug)]
enum Take {
    All,
    Below { limit: f64, test: MprTest },
}

/// The closure's corrections with reusable buffers: one per pass (or per
/// thread), called for every sphere.
#[derive(Clone, Debug)]
pub struct SurfaceCorrections {
    isa: Isa,
    blocks: Vec<ReceiverBlock>,
    /// The contacts that pressed, in order.
    sources: Vec<usize>,
}

impl Default for SurfaceCorrections {
    fn default() -> Self {
        Self::on(Isa::detect())
    }
}

impl SurfaceCorrections {
    /// The kernel on `isa` (the portable build if the processor lacks it).
    pub fn on(isa: Isa) -> Self {
        Self {
            isa: if isa.available() { isa } else { Isa::Portable },
            blocks: Vec::new(),
            sources: Vec::new(),
        }
    }

    /// [`super::surface_corrections`]: the correction of each of one
    /// sphere's `contacts` (radius `radius`) into `corrections` (same
    /// length); returns how many the advanced closure switched off.
    pub fn compute(
        &mut self,
        half_space: &HalfSpace,
        closure: &Closure,
        radius: f64,
        contacts: &[ContactPoint],
        corrections: &mut [f64],
    ) -> usize {
        assert_eq!(contacts.len(), corrections.len());
        self.pack(contacts);
        let (take, switch) = match *closure {
            Closure::Standard => (Take::All, MprSwitch::PerTerm),
            Closure::Advanced {
                max_penetration_ratio,
                switch,
                test,
            } => (
                Take::Below {
                    limit: max_penetration_ratio * radius,
                    test,
                },
                switch,
            ),
        };
        let mut switched_off = 0;
        for (b, block) in self.blocks.iter().enumerate() {
            let sums = self.block_sums(half_space, radius, take, block, contacts);
            let lanes = (contacts.len() - b * LANES).min(LANES);
            for l in 0..lanes {
                let (correction, off) = switch.apply(sums.sum[l], sums.dropped[l]);
                corrections[b * LANES + l] = correction;
                switched_off += off;
            }
        }
        switched_off
    }

    /// Packs every contact as a receiver; the last block's spare lanes
    /// repeat its first receiver, so they form finite sums that are never
    /// read.
    fn pack(&mut self, contacts: &[ContactPoint]) {
        self.sources.clear();
        self.sources
            .extend((0..contacts.len()).filter(|&k| contacts[k].force > 0.0));
        let blocks = contacts.len().div_ceil(LANES);
        self.blocks.clear();
        self.blocks.resize(blocks, ReceiverBlock::default());
        for (b, block) in self.blocks.iter_mut().enumerate() {
            for lane in 0..LANES {
                let c = b * LANES + lane;
                let c = if c < contacts.len() { c } else { b * LANES };
                for d in 0..3 {
                    block.point[d][lane] = contacts[c].point[d];
                    block.normal[d][lane] = contacts[c].normal[d];
                }
                block.contact[lane] = c;
            }
        }
    }

    fn block_sums(
        &self,
        half_space: &HalfSpace,
        radius: f64,
        take: Take,
        block: &ReceiverBlock,
        contacts: &[ContactPoint],
    ) -> BlockSums {
        let compressible = half_space.compressible() != 0.0;
        let standard = matches!(take, Take::All);
        let args = (half_space, radius, take, block, contacts, &self.sources[..]);
        macro_rules! dispatch {
            ($sums:ident $(, $unsafe:tt)?) => {
                $($unsafe)? {
                    match (compressible, standard) {
                        (true, true) => $sums::<true, true>(args),
                        (true, false) => $sums::<true, false>(args),
                        (false, true) => $sums::<false, true>(args),
                        (false, false) => $sums::<false, false>(args),
                    }
                }
            };
        }
        #[cfg(target_arch = "x86_64")]
        if self.isa == Isa::Avx2 {
            // SAFETY: `on` keeps Avx2 only when the processor has it.
            return dispatch!(sums_avx2, unsafe);
        }
        dispatch!(receiver_sums)
    }
}

type SumArgs<'a> = (
    &'a HalfSpace,
    f64,
    Take,
    &'a ReceiverBlock,
    &'a [ContactPoint],
    &'a [usize],
);

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sums_avx2<const COMPRESSIBLE: bool, const STANDARD: bool>(
    args: SumArgs<'_>,
) -> BlockSums {
    receiver_sums::<COMPRESSIBLE, STANDARD>(args)
}

/// Each lane's receiver takes [`HalfSpace::displacement`]'s term (the
/// same function) from every source but itself, in source order;
/// `COMPRESSIBLE` says whether the material's `1 - 2 nu` term is on, and
/// `STANDARD` that every term adds up (`take` is then [`Take::All`]): its
/// lanes add in one vector pass, where the advanced closure's tests and
/// counts go lane by lane.
#[inline(always)]
fn receiver_sums<const COMPRESSIBLE: bool, const STANDARD: bool>(
    (half_space, radius, take, block, contacts, sources): SumArgs<'_>,
) -> BlockSums {
    let coincident = COINCIDENT_POINTS * radius;
    // The one-term loop's empty sum: `Iterator::sum`'s for the standard
    // closure, `0.0` for the advanced.
    let empty = match take {
        Take::All => std::iter::empty::<f64>().sum(),
        Take::Below { .. } => 0.0,
    };
    let mut sums = BlockSums {
        sum: [empty; LANES],
        dropped: [0; LANES],
    };
    for &k in sources {
        let source = (&contacts[k].point, &contacts[k].normal);
        let scaled_force = half_space.scale() * contacts[k].force;
        let mut terms = [0.0; LANES];
        for l in 0..LANES {
            let point = std::array::from_fn(|d| block.point[d][l]);
            let normal = std::array::from_fn(|d| block.normal[d][l]);
            terms[l] = half_space.term::<COMPRESSIBLE>(
                source,
                scaled_force,
                (&point, &normal),
                coincident,
            );
        }
        if STANDARD {
            // Every lane adds, and the one lane whose receiver is the
            // source itself (if this block holds it) gets its sum back. Its
            // term is 0 (coincident points), but 0 turns a sum of -0 (the
            // empty sum, which the one-term loop keeps) into +0.
            let before = sums.sum;
            for l in 0..LANES {
                sums.sum[l] += terms[l];
            }
            let own = k.wrapping_sub(block.contact[0]);
            if own < LANES && block.contact[own] == k {
                sums.sum[own] = before[own];
            }
            continue;
        }
        for l in 0..LANES {
            let t = terms[l];
            let other = block.contact[l] != k;
            let kept = match take {
                Take::All => other,
                Take::Below { limit, test } => {
                    let beyond = match test {
                        MprTest::Magnitude => t.abs() > limit,
                        MprTest::Signed => t > limit,
                    };
                    sums.dropped[l] += usize::from(other && beyond);
                    other && !beyond
                }
            };
            sums.sum[l] = if kept { sums.sum[l] + t } else { sums.sum[l] };
        }
    }
    sums
}

#[cfg(test)]
mod tests {
    use super::super::multicontact::surface_corrections;
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// One sphere's contacts at random points of its surface (some at the
    /// same point, some pressing, some not) with random forces.
    fn random_sphere(rng: &mut ChaCha8Rng, radius: f64, count: usize) -> Vec<ContactPoint> {
        let mut points: Vec<ContactPoint> = Vec::new();
        for _ in 0..count {
            if !points.is_empty() && rng.gen_bool(0.1) {
                let twin = points[rng.gen_range(0..points.len())];
                points.push(twin);
                continue;
            }
            let v: [f64; 3] = std::array::from_fn(|_| rng.gen_range(-1.0..1.0));
            let length = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let depth = radius * rng.gen_range(0.8..1.0);
            let force = if rng.gen_bool(0.3) {
                0.0
            } else {
                rng.gen_range(0.0..2.0)
            };
            points.push(ContactPoint::new(
                v.map(|c| depth * c / length),
                force,
                radius,
            ));
        }
        points
    }

    fn closures() -> Vec<Closure> {
        let mut closures = vec![Closure::Standard];
        for switch in [MprSwitch::WholeContact, MprSwitch::PerTerm] {
            for test in [MprTest::Signed, MprTest::Magnitude] {
                // Terms here are up to about 1e-2 (radius 1e-2): limits of
                // 2e-3 and 5e-3 leave many terms on both sides.
                for max_penetration_ratio in [0.2, 0.5] {
                    closures.push(Closure::Advanced {
                        max_penetration_ratio,
                        switch,
                        test,
                    });
                }
            }
        }
        closures
    }

    #[test]
    fn lanes_give_the_one_term_loops_corrections_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let radius = 1e-2;
        let (mut checked, mut switched) = (0, 0);
        // nu = 1/2 leaves the compressible term out; the others keep it.
        for nu in [0.5, 0.3, -0.2] {
            let half_space = HalfSpace::new(1.125, 5e3, nu);
            for isa in [Isa::Portable, Isa::Avx2] {
                let mut lanes = SurfaceCorrections::on(isa);
                for count in 0..14 {
                    let contacts = random_sphere(&mut rng, radius, count);
                    for closure in closures() {
                        let mut expected = vec![f64::NAN; count];
                        let expected_off = surface_corrections(
                            &half_space,
                            &closure,
                            radius,
                            &contacts,
                            &mut expected,
                        );
                        let mut got = vec![f64::NAN; count];
                        let off = lanes.compute(&half_space, &closure, radius, &contacts, &mut got);
                        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                        assert_eq!(
                            bits(&got),
                            bits(&expected),
                            "{closure:?} nu {nu} {isa:?} {count} contacts"
                        );
                        assert_eq!(off, expected_off);
                        checked += usize::from(expected.iter().any(|&x| x != 0.0));
                        switched += off;
                    }
                }
            }
        }
        assert!(checked > 100, "only {checked} cases had a correction");
        assert!(
            switched > 200,
            "only {switched} contacts or terms switched off"
        );
    }

    #[test]
    fn a_receiver_whose_only_source_is_itself_keeps_the_empty_sum() {
        // Five contacts, only the last pressing: its own correction is the
        // empty sum, -0 in the one-term loop, and must stay -0 in lanes.
        let radius = 1.0;
        let contacts: Vec<ContactPoint> = (0..5)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / 5.0;
                let force = if k == 4 { 1.0 } else { 0.0 };
                ContactPoint::new([a.cos(), a.sin(), 0.0], force, radius)
            })
            .collect();
        let half_space = HalfSpace::new(1.0, 1.0, 0.3);
        let mut expected = [f64::NAN; 5];
        surface_corrections(
            &half_space,
            &Closure::Standard,
            radius,
            &contacts,
            &mut expected,
        );
        assert_eq!(expected[4].to_bits(), (-0.0f64).to_bits());
        for isa in [Isa::Portable, Isa::Avx2] {
            let mut got = [f64::NAN; 5];
            SurfaceCorrections::on(isa).compute(
                &half_space,
                &Closure::Standard,
                radius,
                &contacts,
                &mut got,
            );
            assert_eq!(got.map(f64::to_bits), expected.map(f64::to_bits), "{isa:?}");
        }
    }

    #[test]
    fn the_advanced_closure_switches_contacts_off_in_lanes_too() {
        // Three contacts near the equator pressed hard: each term exceeds
        // a small MPR, so the whole-contact switch zeroes every correction.
        let radius = 1.0;
        let contacts: Vec<ContactPoint> = (0..3)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / 3.0;
                ContactPoint::new([a.cos(), a.sin(), 0.0], 1e3, radius)
            })
            .collect();
        let half_space = HalfSpace::new(1.0, 1.0, 0.3);
        let mut out = [f64::NAN; 3];
        let mut lanes = SurfaceCorrections::default();
        let standard = lanes.compute(&half_space, &Closure::Standard, radius, &contacts, &mut out);
        assert_eq!(standard, 0);
        assert!(out.iter().all(|&d| d.abs() > 1e-3), "{out:?}");
        let advanced = Closure::Advanced {
            max_penetration_ratio: 1e-6,
            switch: MprSwitch::WholeContact,
            test: MprTest::Magnitude,
        };
        let off = lanes.compute(&half_space, &advanced, radius, &contacts, &mut out);
        assert_eq!((off, out), (3, [0.0; 3]));
    }
}
