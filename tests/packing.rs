//! Packings of grains and their analysis: shapes with known answers, a
//! hand-built contact network, and a small built packing.

mod common;

use bpm::analysis::packing::{
    analyse, coordination, monte_carlo_volume_fraction, reference_of, AnalysisOptions, Grains,
    Hull, HullError, Snapshot,
};
use bpm::engine::SimBox;
use bpm::scene::builders::grain::GrainKind;
use bpm::scene::builders::packing::{build_packing, PackingParams};
use rand::{Rng, SeedableRng};

fn cube_box(l: f64) -> SimBox {
    SimBox {
        lo: [0.0; 3],
        lengths: [l; 3],
        tilt: [0.0; 3],
        periodic: [true; 3],
    }
}

/// Points on a sphere of radius `r` (uniform directions), plus its centre.
fn sphere_points(n: usize, r: f64, centre: [f64; 3], seed: u64) -> Vec<[f64; 3]> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut pts = vec![centre];
    while pts.len() < n {
        let v: [f64; 3] = [0, 1, 2].map(|_| rng.gen::<f64>() * 2.0 - 1.0);
        let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if norm > 1e-3 && norm <= 1.0 {
            pts.push([0, 1, 2].map(|k| centre[k] + r * v[k] / norm));
        }
    }
    pts
}

#[test]
fn hull_of_a_cube_has_its_volume_area_and_asphericity() {
    let a = 2.0;
    let mut pts: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                (i & 1) as f64 * a,
                ((i >> 1) & 1) as f64 * a,
                ((i >> 2) & 1) as f64 * a,
            ]
        })
        .collect();
    // Interior points must not change the hull.
    pts.push([1.0, 1.0, 1.0]);
    pts.push([0.5, 1.5, 0.2]);
    let h = Hull::of(&pts).unwrap();
    assert!((h.volume - 8.0).abs() < 1e-12, "{}", h.volume);
    assert!((h.area - 24.0).abs() < 1e-12, "{}", h.area);
    let cube = 6f64.powf(1.5) / (6.0 * std::f64::consts::PI.sqrt());
    assert!((h.asphericity() - cube).abs() < 1e-12);
    assert!(h.contains_offset(&[0.99, 0.99, -0.99]));
    assert!(!h.contains_offset(&[1.01, 0.0, 0.0]));
}

#[test]
fn hull_of_a_sampled_sphere_approaches_the_sphere() {
    let r = 3.0;
    let h = Hull::of(&sphere_points(4000, r, [1.0, 2.0, 3.0], 7)).unwrap();
    let v = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let a = 4.0 * std::f64::consts::PI * r * r;
    // An inscribed polyhedron: a little smaller than the sphere.
    assert!(h.volume < v && h.volume > 0.99 * v, "{} vs {v}", h.volume);
    assert!(h.area < a && h.area > 0.99 * a, "{} vs {a}", h.area);
    let alpha = h.asphericity();
    assert!(alpha > 1.0 && alpha < 1.005, "{alpha}");
}

#[test]
fn degenerate_point_sets_have_no_hull() {
    assert_eq!(
        Hull::of(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]).unwrap_err(),
        HullError::TooFewPoints(3)
    );
    let flat: Vec<[f64; 3]> = (0..9)
        .map(|i| [(i % 3) as f64, (i / 3) as f64, 0.0])
        .collect();
    assert!(matches!(Hull::of(&flat), Err(HullError::Degenerate(_))));
    let line: Vec<[f64; 3]> = (0..9).map(|i| [i as f64, 0.0, 0.0]).collect();
    assert!(matches!(Hull::of(&line), Err(HullError::Degenerate(_))));
    let mut nan = flat.clone();
    nan.push([0.0, 0.0, f64::NAN]);
    assert!(matches!(Hull::of(&nan), Err(HullError::Degenerate(_))));
}

#[test]
fn monte_carlo_volume_fraction_of_known_spheres_is_within_its_error() {
    // Eight non-overlapping spheres of radius 2 (as particles of radius 2)
    // and one hull-only cube straddling a periodic face.
    let l = 12.0;
    let simbox = cube_box(l);
    let x: Vec<[f64; 3]> = (0..8)
        .map(|i| [0, 1, 2].map(|k| if (i >> k) & 1 == 1 { 3.0 } else { 9.0 }))
        .collect();
    let cube: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                (i & 1) as f64 * 2.0 - 1.0,
                ((i >> 1) & 1) as f64 * 2.0 + 5.0,
                ((i >> 2) & 1) as f64 * 2.0 + 5.0,
            ]
        })
        .collect();
    let hulls = vec![Hull::of(&cube).unwrap()];
    let exact = (8.0 * 4.0 / 3.0 * std::f64::consts::PI * 8.0 + 8.0) / l.powi(3);
    let f = monte_carlo_volume_fraction(&simbox, &hulls, &x, 2.0, 400_000, 3);
    assert!(
        (f.phi - exact).abs() < 4.0 * f.error,
        "{} +- {} vs {exact}",
        f.phi,
        f.error
    );
    assert!(f.error < 1e-3);
    // Independent of the thread count: chunks are seeded by index.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let g = one.install(|| monte_carlo_volume_fraction(&simbox, &hulls, &x, 2.0, 400_000, 3));
    assert_eq!(f, g);
    // A wrong radius is caught.
    let h = monte_carlo_volume_fraction(&simbox, &hulls, &x, 1.9, 400_000, 3);
    assert!((h.phi - exact).abs() > 4.0 * h.error);
}

#[test]
fn coordination_of_a_hand_built_network_removes_rattlers_repeatedly() {
    // A tetrahedron (each grain 3 contacts), a grain hanging on it by two
    // contacts (rattler), and a chain 5-6-7 attached to grain 4 only.
    let pairs = [
        [0, 1],
        [0, 2],
        [0, 3],
        [1, 2],
        [1, 3],
        [2, 3],
        [4, 0],
        [4, 1],
        [4, 5],
        [5, 6],
        [6, 7],
    ];
    let c = coordination(8, &pairs, 2);
    assert_eq!(c.rattlers, 4);
    assert_eq!(c.grains, 4);
    assert_eq!(c.z, 3.0);
    // With no rattler rule, every contact counts: 22 ends over 8 grains.
    let all = coordination(8, &pairs, 0);
    assert_eq!(all.rattlers, 0);
    assert!((all.z - 22.0 / 8.0).abs() < 1e-15);
}

#[test]
fn grains_crossing_periodic_faces_come_out_whole() {
    let simbox = cube_box(10.0);
    // A chain of particles 0.9 apart crossing x = 10, wrapped.
    let raw: Vec<[f64; 3]> = (0..6).map(|i| [8.0 + 0.9 * i as f64, 5.0, 5.0]).collect();
    let wrapped: Vec<[f64; 3]> = raw.iter().map(|x| [x[0] % 10.0, x[1], x[2]]).collect();
    let bonds: Vec<[usize; 2]> = (0..5).map(|i| [i, i + 1]).collect();
    let g = Grains::from_bonds(&simbox, &wrapped, &[0; 6], &bonds).unwrap();
    for (a, b) in g.positions[0].iter().zip(&raw) {
        assert!((a[0] - b[0]).abs() < 1e-12, "{a:?} {b:?}");
    }
    assert!((g.centres[0][0] - 10.25).abs() < 1e-12);
    assert!(Grains::from_bonds(&simbox, &wrapped, &[0, 0, 0, 2, 2, 2], &bonds).is_err());
}

#[test]
fn a_built_packing_is_contact_free_and_its_first_state_is_the_reference() {
    let mut params = PackingParams::new(16, GrainKind::Rough, 2.0, 0.0, 5);
    params.grain.time_scale = 0.05;
    params.distinct_grains = 2;
    let (scene, summary) = build_packing(&params, 1, false).unwrap();
    // Bit for bit again: same seed, same threads, same packing.
    let (again, _) = build_packing(&params, 1, false).unwrap();
    assert_eq!(again.particles.positions, scene.particles.positions);
    assert_eq!(again.simbox, scene.simbox);
    let mut runnable = scene.clone();
    runnable.stages = vec![bpm::scene::StageSpec::hold("hold", 1, 0.1)];
    bpm::scene::validate(&runnable).unwrap();
    assert_eq!(summary.grains, 16);
    let grain = scene.particles.grain.clone().unwrap();
    assert_eq!(grain.iter().max(), Some(&15));
    let simbox = bpm::scene::validate::simbox_of(&scene);
    let s = Snapshot {
        simbox: &simbox,
        positions: &scene.particles.positions,
        grain: &grain,
        bonds: &scene.bonds.pairs,
    };
    let opts = AnalysisOptions {
        mc_points: 200_000,
        ..AnalysisOptions::default()
    };
    let reference = reference_of(&s, &opts).unwrap();
    let state = analyse(&s, &reference, &opts).unwrap();
    assert_eq!(state.force_contacts, 0);
    assert_eq!(state.z_force, 0.0);
    assert_eq!(state.rattlers_force, 16);
    assert!(state.eps_v.iter().all(|e| e.abs() < 1e-12));
    assert!(state.asphericity_excess_mean.abs() < 1e-12);
    // Grain 0 shrunk by 0.9 about its centre loses 1 - 0.9^3 of its hull;
    // grain 1 stretched along x becomes less spherical.
    let mut deformed = scene.particles.positions.clone();
    let centre = |g: u32| {
        let m: Vec<&[f64; 3]> = deformed_members(&scene, g);
        let n = m.len() as f64;
        [0, 1, 2].map(|k| m.iter().map(|x| x[k]).sum::<f64>() / n)
    };
    let (c0, c1) = (centre(0), centre(1));
    for (x, &g) in deformed.iter_mut().zip(&grain) {
        if g == 0 {
            *x = [0, 1, 2].map(|k| c0[k] + 0.9 * (x[k] - c0[k]));
        } else if g == 1 {
            x[0] = c1[0] + 1.2 * (x[0] - c1[0]);
        }
    }
    let d = Snapshot {
        positions: &deformed,
        ..s
    };
    let changed = analyse(&d, &reference, &opts).unwrap();
    assert!(
        (changed.eps_v[0] - (1.0 - 0.729)).abs() < 1e-9,
        "{}",
        changed.eps_v[0]
    );
    assert!(
        (changed.eps_v[1] + 0.2).abs() < 1e-9,
        "{}",
        changed.eps_v[1]
    );
    assert!(changed.asphericity[1] > reference.asphericities[1] + 1e-3);
    assert!((changed.asphericity[0] - reference.asphericities[0]).abs() < 1e-9);
    assert!(changed.eps_v[2..].iter().all(|e| e.abs() < 1e-12));
    // The template spheres hold the grains' volume: phi_MC is the template
    // fraction diluted by the expansion that gave the grains room (a few
    // percent either way: grains differ from their mean R_eq), and below
    // the fraction of the grains' outer spheres.
    let expected = 0.57 / summary.expansion.powi(3);
    assert!((summary.sphere_fraction - expected).abs() < 1e-12);
    assert!(
        summary.expansion >= 1.0 && summary.expansion < 1.2,
        "{summary:?}"
    );
    assert!(
        (state.phi_mc / expected - 1.0).abs() < 0.05,
        "{} vs {expected}",
        state.phi_mc
    );
    assert!(state.phi_mc < state.phi_sphere, "{state:?}");
}

#[test]
fn a_packing_data_file_round_trips_and_wrapped_grains_come_out_whole() {
    use bpm::scene::datafile::{read_data_file, write_data_file};
    let mut params = PackingParams::new(16, GrainKind::Rough, 2.0, 0.0, 9);
    params.grain.time_scale = 0.05;
    params.distinct_grains = 1;
    let (scene, _) = build_packing(&params, 1, false).unwrap();
    let dir = common::scratch_dir("packing-data");
    let path = dir.join("packing.data");
    std::fs::write(&path, write_data_file(&scene)).unwrap();
    let back = read_data_file(&path, [true; 3], scene.force_field.clone(), scene.seed).unwrap();
    assert_eq!(back.particles.positions, scene.particles.positions);
    assert_eq!(back.particles.grain, scene.particles.grain);
    assert_eq!(back.bonds.pairs, scene.bonds.pairs);
    assert_eq!(back.simbox, scene.simbox);
    // The same packing with every particle wrapped into the box (as LAMMPS
    // writes it without image flags): grains are made whole through their
    // bonds, so the analysis sees the same hulls.
    let simbox = bpm::scene::validate::simbox_of(&scene);
    let mut wrapped = scene.particles.positions.clone();
    for x in &mut wrapped {
        simbox.wrap(x, &mut [0; 3]);
    }
    assert_ne!(
        wrapped, scene.particles.positions,
        "no grain crossed a face"
    );
    let grain = scene.particles.grain.clone().unwrap();
    let opts = AnalysisOptions {
        mc_points: 100_000,
        ..AnalysisOptions::default()
    };
    let snap = |x: &[[f64; 3]]| {
        reference_of(
            &Snapshot {
                simbox: &simbox,
                positions: x,
                grain: &grain,
                bonds: &scene.bonds.pairs,
            },
            &opts,
        )
        .unwrap()
    };
    let (a, b) = (snap(&scene.particles.positions), snap(&wrapped));
    for (va, vb) in a.hull_volumes.iter().zip(&b.hull_volumes) {
        assert!((va - vb).abs() < 1e-9 * va, "{va} {vb}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn jamming_point_and_exponents_are_recovered_from_synthetic_power_laws() {
    use bpm::analysis::jamming::{coordination_law, power_law_with_jamming_point};
    // States geometric in phi - phi_c from 1e-4 to 0.3, with 1% noise
    // (seeded) on P and a crossover beyond 0.1 that the window leaves out.
    let phi_c = 0.5979;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut phi = Vec::new();
    let mut p = Vec::new();
    let mut z = Vec::new();
    for k in 0..40 {
        let dphi = 1e-4 * (3000f64).powf(k as f64 / 39.0);
        let noise = 1.0 + 0.01 * (rng.gen::<f64>() - 0.5);
        let crossover = if dphi > 0.1 {
            (dphi / 0.1).powi(2)
        } else {
            1.0
        };
        phi.push(phi_c + dphi);
        p.push(0.3 * dphi.powf(1.5) * noise * crossover);
        z.push(5.2 + 8.0 * dphi.sqrt());
    }
    let fit = power_law_with_jamming_point(&phi, &p, 0.1, 0.05, 5).unwrap();
    assert!((fit.phi_c - phi_c).abs() < 2e-5, "{fit:?}");
    assert!(
        (fit.exponent - 1.5).abs() < 3.0 * fit.exponent_error + 0.01,
        "{fit:?}"
    );
    assert!(fit.exponent_error < 0.01);
    // The crossover (dphi / 0.1)^2 exceeds 1.25 from dphi = 0.112; the
    // states are 23% apart, so the first one above lies below 0.138.
    let departure = bpm::analysis::jamming::departure(&phi, &p, &fit, 1.25).unwrap();
    assert!(departure > 0.11 && departure < 0.138, "{departure}");
    let (zfit, z_c) = coordination_law(&phi, &z, fit.phi_c, 0.1, 5).unwrap();
    assert!((z_c - 5.2).abs() < 0.02, "{z_c}");
    assert!((zfit.exponent - 0.5).abs() < 0.02, "{zfit:?}");
    // A wrong exponent is told apart.
    let p2: Vec<f64> = phi.iter().map(|x| (x - phi_c).powf(2.5)).collect();
    let fit2 = power_law_with_jamming_point(&phi, &p2, 0.1, 0.05, 5).unwrap();
    assert!((fit2.exponent - 2.5).abs() < 0.01, "{fit2:?}");
}

fn deformed_members(scene: &bpm::scene::Scene, g: u32) -> Vec<&[f64; 3]> {
    scene
        .particles
        .positions
        .iter()
        .zip(scene.particles.grain.as_ref().unwrap())
        .filter(|(_, &k)| k == g)
        .map(|(x, _)| x)
        .collect()
}

/// DEM spheres for the comparison sit at the bonded packing's template
/// centres with the grains' volume-equivalent radius: the template's
/// volume fraction (less a tiny expansion), no two touching, one sphere per
/// grain with a grain's mass.
#[test]
fn a_sphere_packing_fills_the_template_without_overlap() {
    use bpm::analysis::packing::analyse_spheres;
    use bpm::scene::builders::packing::build_sphere_packing;
    let mut params = PackingParams::new(16, GrainKind::Rough, 2.0, 0.0, 5);
    params.grain.time_scale = 0.05;
    params.distinct_grains = 2;
    let material = bpm::verify::dem_check_material(false);
    let (scene, summary) = build_sphere_packing(&params, material, 1, false).unwrap();
    assert_eq!(scene.model, bpm::scene::ModelKind::Dem);
    assert_eq!(scene.particles.positions.len(), 16);
    // The template leaves overlaps below 1e-9 diameters, which the
    // expansion removes.
    assert!(summary.expansion >= 1.0 && summary.expansion < 1.0 + 1e-8);
    let expected = params.template_fraction / summary.expansion.powi(3);
    assert!((summary.sphere_fraction - expected).abs() < 1e-12);
    let radius = summary.template_radius;
    assert_eq!(scene.particles.radius, Some(vec![radius; 16]));
    let simbox = bpm::scene::validate::simbox_of(&scene);
    let opts = AnalysisOptions {
        mc_points: 200_000,
        ..AnalysisOptions::default()
    };
    let state = analyse_spheres(&simbox, &scene.particles.positions, radius, &opts).unwrap();
    let image = simbox.minimum_image();
    let x = &scene.particles.positions;
    for i in 0..16 {
        for j in i + 1..16 {
            let r = bpm::kernels::Separation::distance(&image, &x[i], &x[j]);
            assert!(r > 2.0 * radius, "spheres {i} and {j} at {r}");
        }
    }
    // Without overlaps the union is the sum of the spheres.
    assert_eq!(state.force_contacts, 0);
    assert!((state.phi_mc - state.phi_sphere).abs() < 4.0 * state.phi_mc_error);
    let mut runnable = scene.clone();
    runnable.stages = vec![bpm::scene::StageSpec::hold("hold", 1, 0.1)];
    bpm::scene::validate(&runnable).unwrap();
    // A rough grain of R = 2 d holds a few dozen unit-mass particles.
    let mass = scene.particles.mass.values(16)[0];
    assert!(mass > 20.0 && mass < 60.0, "{mass}");
}

/// `separate_spheres` expands overlapping polydisperse spheres just enough:
/// afterwards no pair overlaps and the closest pair touches to 1e-8; two
/// spheres at one point are refused.
#[test]
fn overlapping_spheres_are_separated_just_enough() {
    use bpm::scene::builders::packing::separate_spheres;
    let mut scene = bpm::verify::dem_lattice(3, false);
    let before = scene.simbox.lengths;
    let factor = separate_spheres(&mut scene).unwrap();
    assert!(factor > 1.0 && factor < 1.2, "{factor}");
    for (after, before) in scene.simbox.lengths.iter().zip(before) {
        assert!((after - before * factor).abs() < 1e-12 * before);
    }
    let radii = scene.particles.radius.clone().unwrap();
    let simbox = bpm::scene::validate::simbox_of(&scene);
    let image = simbox.minimum_image();
    let x = &scene.particles.positions;
    let mut tightest = f64::INFINITY;
    for i in 0..x.len() {
        for j in i + 1..x.len() {
            let r = bpm::kernels::Separation::distance(&image, &x[i], &x[j]);
            let gap = r / (radii[i] + radii[j]);
            assert!(gap > 1.0, "spheres {i} and {j}: {gap}");
            tightest = tightest.min(gap);
        }
    }
    assert!(tightest < 1.0 + 1e-8, "{tightest}");
    assert_eq!(separate_spheres(&mut scene).unwrap(), 1.0);
    scene.particles.positions[1] = scene.particles.positions[0];
    let e = separate_spheres(&mut scene).unwrap_err();
    assert!(
        e.to_string().contains("spheres 0 and 1 sit at one point"),
        "{e}"
    );
}
