//! The native engine: conservation, determinism, drivers, the bulk builder.

mod common;

use bpm::engine::{Barostat, ExternalTerms, FlatWall, StageDrivers, Tether, WallSide};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::{build_system, run_scene, ForceField, Mass, RunOptions, Scene, StageSpec};
use std::sync::OnceLock;

/// A small bulk solid (L = 5 d, shortened build), built once per test binary.
fn small_solid() -> &'static Scene {
    static SOLID: OnceLock<Scene> = OnceLock::new();
    SOLID.get_or_init(|| {
        build_bulk(&BulkParams::shortened(5.0, 4, 0.0), 1, false)
            .expect("bulk build")
            .0
    })
}

fn solid_with(ff: ForceField, stages: Vec<StageSpec>) -> Scene {
    let mut s = small_solid().clone();
    s.force_field = ff;
    s.stages = stages;
    s
}

fn opts(threads: usize) -> RunOptions {
    RunOptions::quiet(threads)
}

#[test]
fn bulk_builder_reaches_about_fifteen_bonds_per_particle() {
    let s = small_solid();
    let n = s.particles.positions.len();
    let expected = (0.64f64 * 125.0 / (std::f64::consts::PI / 6.0)).round() as usize;
    assert_eq!(n, expected);
    let per = 2.0 * s.bonds.pairs.len() as f64 / n as f64;
    assert!((12.0..17.0).contains(&per), "bonds per particle {per}");
    assert!(s.particles.velocities.is_none(), "velocities are zeroed");
}

#[test]
fn bulk_builder_is_repeatable_and_seed_dependent() {
    let mut p = BulkParams::paper(4.0, 9, 0.0);
    p.relax_time = 5.0;
    p.thermal_time = 5.0;
    p.quench_time = 5.0;
    let a = build_bulk(&p, 1, false).unwrap().0;
    let b = build_bulk(&p, 1, false).unwrap().0;
    assert_eq!(a.particles.positions, b.particles.positions);
    p.seed = 10;
    let c = build_bulk(&p, 1, false).unwrap().0;
    assert_ne!(a.particles.positions, c.particles.positions);
}

#[test]
fn undamped_spring_network_conserves_energy() {
    let mut ff = ForceField::paper(0.0);
    ff.bond.gamma = 0.0;
    ff.pair = ff
        .pair
        .map(|p| bpm::kernels::PairCoeffs { gamma: 0.0, ..p });
    let mut hold = StageSpec::hold("nve", 2000, 0.05);
    hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.02 });
    hold.record.every = 100;
    let scene = solid_with(ff, vec![hold]);
    let mut sys = build_system(&scene, 1);
    let (out, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    let st = &out[0];
    let total: Vec<f64> = ["e_bond", "e_pair", "e_kinetic"]
        .iter()
        .map(|c| st.column(c).unwrap())
        .fold(vec![0.0; st.rows.len()], |acc, c| {
            acc.iter().zip(&c).map(|(a, b)| a + b).collect()
        });
    let e0 = total[0];
    let drift = total.iter().map(|e| (e - e0).abs()).fold(0.0, f64::max);
    assert!(e0 > 0.0);
    assert!(drift < 2e-3 * e0, "energy drift {drift} of {e0}");
}

#[test]
fn damped_multibody_dynamics_conserve_momentum() {
    let mut hold = StageSpec::hold("md", 50, 0.1);
    hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.05 });
    let scene = solid_with(ForceField::paper(-0.5), vec![hold]);
    let mut sys = build_system(&scene, 1);
    let (_, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    let mut p = [0.0f64; 3];
    for v in &sys.particles.v {
        for d in 0..3 {
            p[d] += v[d];
        }
    }
    assert!(sys.kinetic_energy() > 1e-6, "the system must still move");
    assert!(p.iter().all(|c| c.abs() < 1e-12), "net momentum {p:?}");
}

#[test]
fn runs_are_bit_for_bit_repeatable_and_thread_counts_agree() {
    let mut hold = StageSpec::hold("md", 200, 0.1);
    hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.05 });
    let scene = solid_with(ForceField::paper(0.8), vec![hold]);
    let run = |threads| {
        let mut sys = build_system(&scene, threads);
        let (_, err) = run_scene(&mut sys, &scene, &opts(threads));
        assert!(err.is_none());
        sys.particles.x
    };
    let a = run(2);
    assert_eq!(a, run(2), "same thread count must be bit-identical");
    let serial = run(1);
    let dev = a
        .iter()
        .zip(&serial)
        .flat_map(|(p, q)| (0..3).map(move |d| (p[d] - q[d]).abs()))
        .fold(0.0, f64::max);
    assert!(dev < 1e-9, "1 vs 2 threads differ by {dev} after 200 steps");
}

/// The bond pass sums each particle's bond forces in one fixed order
/// whatever the number of threads: with no contacts (whose pass splits
/// its list between threads), runs on 1, 2 and 3 threads are identical
/// bit for bit, with the multibody term, damping and bonds across the
/// periodic faces.
#[test]
fn bond_forces_do_not_depend_on_the_thread_count() {
    let mut hold = StageSpec::hold("md", 100, 0.1);
    hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.05 });
    let mut ff = ForceField::paper(-0.5);
    ff.pair = None;
    let scene = solid_with(ff, vec![hold]);
    let run = |threads| {
        let mut sys = build_system(&scene, threads);
        let (_, err) = run_scene(&mut sys, &scene, &opts(threads));
        assert!(err.is_none());
        (sys.particles.x, sys.particles.f)
    };
    let serial = run(1);
    assert!(serial.1.iter().flatten().any(|&f| f != 0.0));
    assert_eq!(run(2), serial, "2 threads");
    assert_eq!(run(3), serial, "3 threads");
}

/// The barostat's scalar pressure, `(sum m v^2 + W_xx + W_yy + W_zz) / 3 /
/// V` in LAMMPS's order, on a moving, loaded solid of unequal masses: on one
/// thread exactly that, from the kinetic energy's own sum; on two and three
/// threads, whose shares of `sum m v^2` are summed by the thread that holds
/// them, the same to round-off.
#[test]
fn scalar_pressure_sums_the_kinetic_part_per_thread_to_round_off() {
    let mut hold = StageSpec::hold("md", 20, 0.1);
    hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.05 });
    let mut ff = ForceField::paper(-0.5);
    ff.pair = None;
    let mut scene = solid_with(ff, vec![hold]);
    let n = scene.particles.positions.len();
    let masses = (0..n).map(|p| 1.0 + 0.5 * (p % 3) as f64).collect();
    scene.particles.mass = Mass::PerParticle(masses);
    let pressure = |threads| {
        let mut sys = build_system(&scene, threads);
        let (_, err) = run_scene(&mut sys, &scene, &opts(threads));
        assert!(err.is_none());
        // Forces and their virial once more, at the final state.
        sys.setup(&StageDrivers {
            dt: 0.1,
            ..Default::default()
        })
        .unwrap();
        let sum_mv2 = 2.0 * sys.kinetic_energy();
        let dof = (3 * sys.len()) as f64 - 3.0;
        let w = sys.interaction_tally().virial;
        let [lx, ly, lz] = sys.simbox.lengths;
        let formula =
            (dof * (sum_mv2 * (1.0 / dof)) + w[0] + w[1] + w[2]) / 3.0 * (1.0 / (lx * ly * lz));
        let parts = [sum_mv2, w[0] + w[1] + w[2]].map(|c| c / 3.0 / (lx * ly * lz));
        (sys.scalar_pressure(), formula, parts)
    };
    let (serial, formula, [kinetic, virial]) = pressure(1);
    assert_eq!(serial, formula);
    for part in [kinetic, virial] {
        assert!(
            part.abs() > 1e-3 * serial.abs(),
            "kinetic part {kinetic}, virial part {virial} of {serial}"
        );
    }
    for threads in [2, 3] {
        let (p, _, _) = pressure(threads);
        assert!(
            (p - serial).abs() <= 1e-14 * serial.abs(),
            "{threads} threads: {p} against {serial}"
        );
    }
}

#[test]
fn affine_isotropic_compression_loads_springs_but_not_the_multibody_term() {
    let scene = solid_with(ForceField::paper(0.0), vec![StageSpec::hold("h", 1, 0.1)]);
    let pressure_after_squeeze = |a_b: f64| {
        let mut s = scene.clone();
        s.force_field = ForceField::paper(a_b);
        let mut sys = build_system(&s, 1);
        let mut b = sys.simbox.clone();
        b.resize_about_centre(b.lengths.map(|l| l * 0.995), [0.0; 3]);
        sys.remap_into(b);
        sys.setup(&StageDrivers {
            dt: 0.1,
            ..Default::default()
        })
        .unwrap();
        sys.pressure()
    };
    let p0 = pressure_after_squeeze(0.0);
    let p1 = pressure_after_squeeze(1.5);
    assert!(p0 > 1e-3, "compression gives positive pressure: {p0}");
    assert!((p0 - p1).abs() < 1e-12 * p0, "{p0} vs {p1}");
}

#[test]
fn simple_shear_by_tilt_gives_shear_stress_of_the_right_sign() {
    let mut shear = bpm::scene::protocols::simple_shear(0.002, 1e-4, 0.1, 4);
    shear.record.every = shear.steps;
    let scene = solid_with(ForceField::paper(0.0), vec![shear]);
    let mut sys = build_system(&scene, 1);
    let (out, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    let pxy = out[0].column("pxy").unwrap();
    let xy = out[0].column("xy").unwrap();
    assert!(
        (xy.last().unwrap() - 0.002 * 5.0).abs() < 1e-9,
        "tilt reached {:?}",
        xy.last()
    );
    assert!(
        *pxy.last().unwrap() < 0.0,
        "positive shear strain gives negative P_xy: {pxy:?}"
    );
}

fn single_particle(z: f64) -> Scene {
    let mut s = small_solid().clone();
    s.simbox.periodic = [true, true, false];
    s.particles.positions = vec![[1.0, 1.0, z]];
    s.particles.velocities = None;
    s.bonds = Default::default();
    s
}

#[test]
fn flat_wall_pushes_with_k_times_overlap_and_reports_it() {
    let mut stage = StageSpec::hold("wall", 1, 0.1);
    stage.walls.push(FlatWall {
        axis: 2,
        side: WallSide::Lo,
        position: 0.0,
        velocity: 0.0,
        stiffness: 2.0,
        cutoff: 1.0,
    });
    stage.walls.push(FlatWall {
        axis: 2,
        side: WallSide::Hi,
        position: 1.5,
        velocity: 0.0,
        stiffness: 2.0,
        cutoff: 1.0,
    });
    let mut scene = single_particle(0.75);
    scene.stages = vec![stage.clone()];
    let mut sys = build_system(&scene, 1);
    let drivers = StageDrivers {
        dt: 0.1,
        external: ExternalTerms {
            walls: stage.walls.clone(),
            ..Default::default()
        },
        ..Default::default()
    };
    sys.setup(&drivers).unwrap();
    assert_eq!(
        sys.report.external.wall_forces,
        vec![2.0 * 0.25, 2.0 * 0.25]
    );
    assert!(
        sys.particles.f[0][2].abs() < 1e-15,
        "symmetric walls cancel"
    );
    // Moving the lower wall up by 0.1 raises its force by k * 0.1.
    sys.compute_forces(
        &StageDrivers {
            external: ExternalTerms {
                walls: vec![FlatWall {
                    velocity: 1.0,
                    ..stage.walls[0].clone()
                }],
                ..Default::default()
            },
            ..drivers
        },
        0.1,
        true,
    );
    assert!((sys.report.external.wall_forces[0] - 2.0 * 0.35).abs() < 1e-14);
    assert!((sys.particles.f[0][2] - 2.0 * 0.35).abs() < 1e-14);
}

#[test]
fn tether_pulls_the_centre_of_mass_back_to_its_anchor() {
    let mut scene = single_particle(2.0);
    let mut stage = StageSpec::hold("tether", 1, 0.1);
    stage.tether = Some(Tether {
        grain: None,
        anchor: Some([0.5, 1.0, 2.0]),
        dims: [true, true, false],
        stiffness: 0.1,
    });
    scene.stages = vec![stage];
    let mut sys = build_system(&scene, 1);
    let (_, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    // One step of dt 0.1 from rest under F = -0.1 (x - 0.5) = -0.05 (half kicks).
    assert!((sys.particles.f[0][0] + 0.1 * (sys.particles.x[0][0] - 0.5)).abs() < 1e-12);
    assert!(sys.particles.v[0][0] < 0.0 && sys.particles.f[0][2] == 0.0);
}

#[test]
fn berendsen_barostat_relaxes_a_compressed_solid_towards_the_target() {
    let mut b = StageSpec::hold("baro", 600, 0.1);
    b.barostat = Some(Barostat {
        target_pressure: 0.0,
        gain: 0.05,
    });
    b.record.every = 600;
    let mut scene = solid_with(ForceField::paper(0.0), vec![b]);
    let squeeze = 0.99;
    for p in &mut scene.particles.positions {
        *p = p.map(|c| c * squeeze);
    }
    scene.simbox.lengths = scene.simbox.lengths.map(|l| l * squeeze);
    let mut sys = build_system(&scene, 1);
    let (out, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    let p = out[0].column("pressure").unwrap();
    assert!(p[0] > 1e-3, "starts compressed: {p:?}");
    assert!(p[1].abs() < 0.1 * p[0], "relaxes towards 0: {p:?}");
    assert!(sys.simbox.lengths[0] > 5.0 * squeeze);
}

#[test]
fn an_unstable_run_stops_with_an_error_and_keeps_finished_stages() {
    let mut ok = StageSpec::hold("fine", 10, 0.1);
    ok.record.every = 5;
    let mut bad = StageSpec::hold("explode", 2000, 50.0);
    bad.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 1.0 });
    let mut ff = ForceField::paper(0.0);
    ff.bond.gamma = 0.0;
    let scene = solid_with(ff, vec![ok, bad]);
    let mut sys = build_system(&scene, 1);
    let (out, err) = run_scene(&mut sys, &scene, &opts(1));
    assert_eq!(
        out.len(),
        2,
        "the finished stage and the failed one are kept"
    );
    assert_eq!(out[0].stopped_at, None);
    assert_eq!(out[0].rows.len(), 3);
    let stopped = out[1]
        .stopped_at
        .expect("the failed stage says where it stopped");
    assert!((1..2000).contains(&stopped), "stopped at {stopped}");
    assert!(
        out[1].rows.iter().flatten().all(|v| v.is_finite()),
        "the kept records are the finite ones"
    );
    let msg = err.expect("dt = 50 must blow up").to_string();
    assert!(msg.contains("unstable"), "{msg}");
}

#[test]
fn bond_split_into_interior_and_boundary_matches_minimum_image_after_wraps() {
    use bpm::kernels::{bond_forces, pair_forces, BondInputs, Ownership, PairInputs};
    // Drift the whole solid so that atoms cross the box and get wrapped,
    // while the box deforms: the interior/boundary split must follow.
    let mut stage = StageSpec::hold("drift", 400, 0.1);
    stage.deformation = Some(bpm::engine::Deformation::SimpleShear {
        tilt: bpm::engine::TiltFactor::Xy,
        rate: 1e-4,
        remap: bpm::engine::ShearRemap::X,
    });
    let mut scene = solid_with(ForceField::paper(-0.5), vec![stage]);
    let n = scene.particles.positions.len();
    scene.particles.velocities = Some(vec![[0.11, -0.07, 0.05]; n]);
    let mut sys = build_system(&scene, 1);
    let (_, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    assert!(
        sys.wraps > 2,
        "atoms must have been wrapped ({} wraps)",
        sys.wraps
    );
    let drivers = StageDrivers {
        dt: 0.1,
        ..Default::default()
    };
    sys.compute_forces(&drivers, 0.0, true);
    // Reference: every bond through the minimum image, no split.
    let sep = sys.simbox.minimum_image();
    let model = sys
        .model_as::<bpm::engine::BpmModel>()
        .expect("a bonded-particle scene");
    let (vol, vol0) = {
        let (a, b) = model.volumes();
        (a.to_vec(), b.to_vec())
    };
    let bonds = model.bonds().clone();
    let mut vol_ref = vec![0.0; n];
    bpm::kernels::accumulate_volumes(
        &sep,
        &sys.particles.x,
        &bonds.entries,
        Ownership::all(n),
        &mut vol_ref,
    );
    for (a, b) in vol.iter().zip(&vol_ref) {
        assert!((a - b).abs() < 1e-12 * b, "volume {a} vs {b}");
    }
    let ff = ForceField::paper(-0.5);
    let coeffs = [ff.bond];
    let mut f = vec![[0.0; 3]; n];
    let inputs = BondInputs {
        x: &sys.particles.x,
        v: Some(&sys.particles.v),
        bonds: &bonds.entries,
        r0: &bonds.r0,
        coeffs: &coeffs,
        volumes: Some((&vol_ref, &vol0)),
        tally: true,
    };
    let tb = bond_forces(&sep, &inputs, Ownership::all(n), &mut f).tally;
    let pcoeffs = [ff.pair.unwrap()];
    let pin = PairInputs {
        x: &sys.particles.x,
        v: Some(&sys.particles.v),
        types: None,
        ntypes: 1,
        coeffs: &pcoeffs,
        special: [1.0; 4],
        tally: true,
        damping_taper: false,
    };
    pair_forces(
        &sep,
        &pin,
        sys.neighbours.rows(0..n),
        Ownership::all(n),
        &mut f,
    );
    // Round-off scale: inside a bond force, terms of size k r0 and a_B D
    // (about 1) cancel to leave about 1e-3, and the split sums volumes and
    // forces in another order, so differences are ulps of these terms.
    let bond_scale = ff.bond.k * bonds.max_r0() + ff.bond.a.abs();
    for (a, b) in sys.particles.f.iter().zip(&f) {
        for d in 0..3 {
            assert!(
                (a[d] - b[d]).abs() < 1e-13 * bond_scale,
                "{a:?} vs {b:?} (bond scale {bond_scale:e})"
            );
        }
    }
    let tsys = sys.report.interactions.terms[bpm::engine::bpm::BOND_TERM];
    let vscale = tb.virial.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for k in 0..6 {
        assert!(
            (tsys.virial[k] - tb.virial[k]).abs() < 1e-12 * vscale,
            "virial[{k}]"
        );
    }
}

/// Copies of a periodic solid side by side are the same solid: every bond
/// keeps its length across the new periodic faces, every particle its bond
/// count, and under the same strain the stress is the same.
#[test]
fn a_replicated_solid_has_the_same_bonds_and_stress() {
    use bpm::kernels::Separation;
    use bpm::scene::builders::replicate::replicate;
    let base = solid_with(ForceField::paper(-0.5), vec![]);
    let copies = [2, 3, 1];
    let big = replicate(&base, copies).unwrap();
    let (n, m) = (base.particles.positions.len(), base.bonds.pairs.len());
    assert_eq!(big.particles.positions.len(), 6 * n);
    assert_eq!(big.bonds.pairs.len(), 6 * m);
    let r0 = big.bonds.r0.as_ref().unwrap();
    let big_box = bpm::scene::validate::simbox_of(&big);
    let x = &big.particles.positions;
    for (k, &[i, j]) in big.bonds.pairs.iter().enumerate() {
        let r = big_box.distance(&x[i], &x[j]);
        assert!(
            (r - r0[k]).abs() < 1e-12,
            "bond {k}: {r} against r0 {}",
            r0[k]
        );
    }
    let mut degree = vec![0usize; 6 * n];
    for &[i, j] in &big.bonds.pairs {
        degree[i] += 1;
        degree[j] += 1;
    }
    for (i, d) in degree.iter().enumerate() {
        assert_eq!(*d, degree[i % n], "particle {i}");
    }
    let strained_pressure = |scene: &Scene| {
        let mut sys = build_system(scene, 1);
        let mut b = sys.simbox.clone();
        b.resize_about_centre(b.lengths.map(|l| l * 0.995), [0.0; 3]);
        sys.remap_into(b);
        sys.setup(&bpm::engine::StageDrivers {
            dt: 0.1,
            ..Default::default()
        })
        .unwrap();
        sys.pressure_tensor()
    };
    let (p1, p6) = (strained_pressure(&base), strained_pressure(&big));
    assert!(p1[0] > 1e-3, "the strain loads the solid: {p1:?}");
    for k in 0..6 {
        assert!(
            (p1[k] - p6[k]).abs() < 1e-12 * p1[0].abs(),
            "{p1:?} against {p6:?}"
        );
    }
    assert!(replicate(&base, [0, 1, 1]).is_err());
}

/// The bond pass in windows (each thread's rows computed into a small ring
/// and gathered block by block) against the full-size array of rows, on
/// the same system: forces and positions equal bit for bit on 1, 2 and 3
/// threads; and on one thread the same virial, so that a barostat, which
/// reads it every step, moves the box the same way to the last bit. With
/// the multibody term and without; the solid's bonds cross the periodic
/// faces, so the boundary rows take part.
#[test]
fn the_windowed_bond_pass_changes_no_bit() {
    use bpm::engine::{BondWindow, BpmModel};
    let solid = build_bulk(&BulkParams::shortened(12.0, 4, 0.0), 2, false)
        .expect("bulk build")
        .0;
    let solid_with = |ff: ForceField, stages: Vec<StageSpec>| Scene {
        force_field: ff,
        stages,
        ..solid.clone()
    };
    let run = |scene: &Scene, threads, mode| {
        let mut sys = build_system(scene, threads);
        let model = sys.model_as_mut::<BpmModel>().expect("a bonded model");
        model.set_bond_window(mode);
        let (_, err) = run_scene(&mut sys, scene, &opts(threads));
        assert!(err.is_none(), "{err:?}");
        let model = sys.model_as::<BpmModel>().expect("a bonded model");
        match model.bond_window() {
            // The ring wraps (on one thread, whose part has every row).
            Some((ring, _)) => assert!(
                threads > 1 || ring < model.bonds().len(),
                "ring {ring}, {} bonds",
                model.bonds().len()
            ),
            None => assert_eq!(mode, BondWindow::Never),
        }
        (sys.particles.x, sys.particles.f, sys.simbox.lengths)
    };
    // The first particle whose position or force differs, if any.
    type Run = (Vec<[f64; 3]>, Vec<[f64; 3]>, [f64; 3]);
    let first_difference = |a: &Run, b: &Run| {
        assert_eq!(a.2, b.2, "box lengths");
        (0..a.0.len()).find(|&p| a.0[p] != b.0[p] || a.1[p] != b.1[p])
    };
    for a_b in [0.0, -0.5] {
        let mut hold = StageSpec::hold("md", 60, 0.1);
        hold.set_velocities = Some(bpm::scene::VelocityInit { rms_speed: 0.05 });
        let scene = solid_with(ForceField::paper(a_b), vec![hold.clone()]);
        for threads in [1, 2, 3] {
            let full = run(&scene, threads, BondWindow::Never);
            assert!(full.1.iter().flatten().any(|&f| f != 0.0));
            let windowed = run(&scene, threads, BondWindow::Always);
            let differ = first_difference(&windowed, &full);
            assert!(
                differ.is_none(),
                "a_B = {a_b}, {threads} thread(s): particle {differ:?}"
            );
        }
        let mut baro = hold;
        baro.barostat = Some(Barostat {
            target_pressure: -1e-3,
            gain: 0.05,
        });
        let scene = solid_with(ForceField::paper(a_b), vec![baro]);
        let full = run(&scene, 1, BondWindow::Never);
        assert_ne!(full.2, scene.simbox.lengths, "the barostat moved the box");
        let differ = first_difference(&run(&scene, 1, BondWindow::Always), &full);
        assert!(
            differ.is_none(),
            "a_B = {a_b}, barostat: particle {differ:?}"
        );
    }
    // The default leaves a solid this small to the full-size array.
    let scene = solid_with(ForceField::paper(0.0), vec![StageSpec::hold("md", 2, 0.1)]);
    let mut sys = build_system(&scene, 1);
    let (_, err) = run_scene(&mut sys, &scene, &opts(1));
    assert!(err.is_none());
    let model = sys.model_as::<BpmModel>().expect("a bonded model");
    assert_eq!(model.bond_window(), None);
}
