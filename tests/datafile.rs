//! LAMMPS data files in and out: a file as LAMMPS's write_data makes it
//! (coefficient sections, unsorted and non-contiguous ids, image flags)
//! imports, exports and imports again to the same scene, keeping its atom
//! ids (also in dumps and the final scene of a run, but not in the LAMMPS
//! harness's own data file); LIGGGHTS sphere files import; what a scene
//! cannot hold is refused with the reason; malformed files name the line.

mod common;

use bpm::scene::datafile::{read_data_file, write_data_file};
use bpm::scene::trajectory::read_dump;
use bpm::scene::{
    build_system, final_scene, run_scene, validate, DumpOptions, ForceField, Mass, ModelKind,
    OutputFiles, RunOptions, StageSpec,
};
use serde_json::json;

const WRITE_DATA: &str = "LAMMPS data file via write_data, version 29 Sep 2021, timestep = 1000

5 atoms
2 atom types
3 bonds
1 bond types
24 extra bond per atom

0 10 xlo xhi
0 10 ylo yhi
-5 5 zlo zhi

Masses

1 1
2 2.5

Pair Coeffs # bpm/contact

1 1 1 50 1
2 1 1 50 1

Bond Coeffs # bpm/multibody

1 1 -0.5 1

Atoms # bond

17 3 1 9.6 5 0 0 0 0
4 3 2 0.4 5 0 1 0 0
9 8 1 5 5 1 0 0 0
30 8 1 5 5.9 1 0 0 0
2 3 1 9.5 5.8 0.2 -1 0 0

Velocities

4 0.1 0 0
2 0 0.2 0
30 0 0 -0.3
17 0 0 0
9 1e-3 0 0

Bonds

1 1 17 4
2 1 9 30
3 1 2 4
";

#[test]
fn write_data_output_imports_exports_and_imports_again_unchanged() {
    let dir = common::scratch_dir("datafile");
    let path = dir.join("grains.data");
    std::fs::write(&path, WRITE_DATA).unwrap();
    let ff = ForceField::paper(-0.5);
    let scene = read_data_file(&path, [true, true, false], ff.clone(), 3).unwrap();
    // Atoms sorted by id: 2, 4, 9, 17, 30.
    let pa = &scene.particles;
    assert_eq!(pa.positions.len(), 5);
    // Molecules 3 and 8 become grains 0 and 1.
    assert_eq!(pa.grain.as_deref(), Some(&[0, 0, 1, 0, 1][..]));
    assert_eq!(pa.kind.as_deref(), Some(&[1, 2, 1, 1, 1][..]));
    assert_eq!(pa.mass, Mass::PerParticle(vec![1.0, 2.5, 1.0, 1.0, 1.0]));
    // Image flags unwrap: atom 2 (ix = -1) sits at x = 9.5 - 10, atom 4
    // (ix = 1) at 0.4 + 10, so grain 0 is whole near x = 10.
    assert_eq!(pa.positions[0], [-0.5, 5.8, 0.2]);
    assert_eq!(pa.positions[1], [10.4, 5.0, 0.0]);
    assert_eq!(pa.velocities.as_ref().unwrap()[0], [0.0, 0.2, 0.0]);
    // Bonds by index; reference lengths are the file's (minimum image):
    // atoms 17 and 4 are 0.8 apart across the periodic x face.
    assert_eq!(scene.bonds.pairs, vec![[3, 1], [2, 4], [0, 1]]);
    let r0 = scene.bonds.r0.as_ref().unwrap();
    assert!((r0[0] - 0.8).abs() < 1e-12, "{r0:?}");
    assert!((r0[1] - 0.9).abs() < 1e-12, "{r0:?}");
    // Export and import again: the same scene, bit for bit.
    let exported = dir.join("exported.data");
    std::fs::write(&exported, write_data_file(&scene)).unwrap();
    let again = read_data_file(&exported, [true, true, false], ff, 3).unwrap();
    assert_eq!(again.particles, scene.particles);
    assert_eq!(again.bonds, scene.bonds);
    assert_eq!(again.simbox, scene.simbox);
    assert_eq!(again.particles.ids, Some(vec![2, 4, 9, 17, 30]));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The atom ids of WRITE_DATA, in the particle order of its scene.
const WRITE_DATA_IDS: [u64; 5] = [2, 4, 9, 17, 30];

/// The lines of section `name` of data file `text` (up to the next blank
/// line after its data).
fn section<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    text.lines()
        .skip_while(|l| !l.starts_with(name))
        .skip(2)
        .take_while(|l| !l.trim().is_empty())
        .collect()
}

#[test]
fn atom_ids_are_kept_through_export_runs_dumps_and_the_final_scene() {
    let dir = common::scratch_dir("datafile-ids");
    let path = dir.join("grains.data");
    std::fs::write(&path, WRITE_DATA).unwrap();
    let mut scene = read_data_file(&path, [true, true, false], ForceField::paper(-0.5), 3).unwrap();
    assert_eq!(scene.particles.ids.as_deref(), Some(&WRITE_DATA_IDS[..]));
    // The exported file numbers atoms, velocities and bonds by those ids.
    let text = write_data_file(&scene);
    let first = |l: &&str| l.split_whitespace().next().unwrap().parse::<u64>().unwrap();
    let atoms: Vec<u64> = section(&text, "Atoms").iter().map(first).collect();
    assert_eq!(atoms, WRITE_DATA_IDS);
    let velocities: Vec<u64> = section(&text, "Velocities").iter().map(first).collect();
    assert_eq!(velocities, WRITE_DATA_IDS);
    assert_eq!(section(&text, "Bonds"), ["1 1 17 4", "2 1 9 30", "3 1 2 4"]);
    // The LAMMPS harness's run file numbers them 1..N (LAMMPS hands atoms
    // back by id), in particle order.
    let run = bpm::lammps::write_run_data_file(&scene);
    let atoms: Vec<u64> = section(&run, "Atoms").iter().map(first).collect();
    assert_eq!(atoms, [1, 2, 3, 4, 5]);
    assert_eq!(section(&run, "Bonds"), ["1 1 4 2", "2 1 3 5", "3 1 1 2"]);
    // A native run: every dump frame and the final scene carry the ids.
    let mut stage = StageSpec::hold("hold", 20, 0.01);
    stage.record.every = 10;
    scene.stages = vec![stage];
    validate(&scene).unwrap();
    let dump = dir.join("run.dump");
    let opts = RunOptions {
        files: OutputFiles {
            thermo: None,
            dump: Some(DumpOptions {
                path: dump.clone(),
                every: 10,
                forces: false,
            }),
        },
        ..RunOptions::quiet(1)
    };
    let mut sys = build_system(&scene, 1);
    let (stages, error) = run_scene(&mut sys, &scene, &opts);
    assert!(error.is_none(), "{error:?}");
    assert_eq!(stages.len(), 1);
    let frames = read_dump(&dump).unwrap();
    assert_eq!(frames.len(), 3);
    for f in &frames {
        assert_eq!(
            f.id.as_deref(),
            Some(&WRITE_DATA_IDS[..]),
            "step {}",
            f.step
        );
    }
    let fin = final_scene(&scene, &sys);
    assert_eq!(fin.particles.ids.as_deref(), Some(&WRITE_DATA_IDS[..]));
    // A file numbered 1..N gives a scene without ids, written as before.
    let plain = dir.join("plain.data");
    std::fs::write(&plain, bpm::lammps::write_run_data_file(&scene)).unwrap();
    let renumbered =
        read_data_file(&plain, [true, true, false], ForceField::paper(-0.5), 3).unwrap();
    assert_eq!(renumbered.particles.ids, None);
    assert_eq!(renumbered.particles.positions, scene.particles.positions);
    let json = serde_json::to_string(&renumbered).unwrap();
    assert!(!json.contains("\"ids\""), "{json}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A LIGGGHTS `write_data` file of spheres (`atom_style sphere`, written as
/// LIGGGHTS writes it: padded header, no style comment, `E-005`
/// exponents, angular velocities in Velocities), atom ids out of order and
/// not 1..N, two types.
const LIGGGHTS_DATA: &str = "LIGGGHTS data file

 4  atoms

 2  atom types

 -0.0101  0.1701 xlo xhi
 -0.0101  0.1701 ylo yhi
 -0.0101  0.4101 zlo zhi

Atoms

3 1 0.0192777 11.5 0.0281955 0.15621 0.0747432
1 1 0.0215912 11.5 0.0872805 0.139893 0.04861
12 2 0.02 1500 0.137187 0.0207118 0.104042
7 1 0.0215856 11.5 0.0709243 0.0107512 0.133165

Velocities

1 -4.79229E-005 0.000000239 0.000131939 0.0 0.0 0.0
3 -0.000104227 -3.58724E-005 2.29323E-005 0.0 0.0 0.0
12 2.33346E-005 0.00011522 4.04167E-005 0.0 0.0 1.5
7 4.49616E-005 1.60183E-006 1.28551E-006 0.0 0.0 0.0
";

fn sphere_material() -> bpm::kernels::GranularMaterial {
    serde_json::from_value(json!({"youngs_modulus": 5e6, "poisson_ratio": 0.25,
        "restitution": 0.5, "tangential_damping": 1, "sliding_friction": 0.3}))
    .unwrap()
}

#[test]
fn liggghts_and_lammps_sphere_files_import() {
    let dir = common::scratch_dir("datafile-liggghts");
    let path = dir.join("input.data");
    std::fs::write(&path, LIGGGHTS_DATA).unwrap();
    let ff = ForceField::dem(sphere_material());
    let scene = read_data_file(&path, [false; 3], ff.clone(), 1).unwrap();
    assert_eq!(scene.model, ModelKind::Dem);
    let pa = &scene.particles;
    // Ordered by id: 1, 3, 7, 12.
    assert_eq!(pa.ids.as_deref(), Some(&[1, 3, 7, 12][..]));
    assert_eq!(pa.kind.as_deref(), Some(&[1, 1, 1, 2][..]));
    assert_eq!(pa.positions[0], [0.0872805, 0.139893, 0.04861]);
    let r = pa.radius.as_deref().unwrap();
    assert_eq!(r, [0.0215912 / 2.0, 0.0192777 / 2.0, 0.0215856 / 2.0, 0.01]);
    // Mass from the density, as LAMMPS forms it.
    let Mass::PerParticle(m) = &pa.mass else {
        panic!("masses differ per sphere: {:?}", pa.mass)
    };
    let sphere = |r: f64, rho: f64| rho * (4.0 * std::f64::consts::PI / 3.0 * r * r * r);
    assert_eq!(m[0], sphere(r[0], 11.5));
    assert_eq!(m[3], sphere(0.01, 1500.0));
    assert_eq!(
        pa.velocities.as_ref().unwrap()[0],
        [-4.79229e-5, 2.39e-7, 0.000131939]
    );
    assert_eq!(pa.angular_velocities.as_ref().unwrap()[3], [0.0, 0.0, 1.5]);
    assert_eq!(scene.simbox.lo, [-0.0101, -0.0101, -0.0101]);
    assert_eq!(scene.simbox.lengths[2], 0.4101 - -0.0101);
    // Exported and read again: the same spheres with the same ids.
    let exported = dir.join("exported.data");
    std::fs::write(&exported, write_data_file(&scene)).unwrap();
    let again = read_data_file(&exported, [false; 3], ff.clone(), 1).unwrap();
    assert_eq!(again.particles.ids, scene.particles.ids);
    assert_eq!(again.particles.positions, scene.particles.positions);
    // LAMMPS's own sphere file: style comment and image flags.
    let lammps = "LAMMPS data file via write_data\n\n2 atoms\n1 atom types\n\n0 4 xlo xhi\n0 4 ylo yhi\n0 4 zlo zhi\n\nAtoms # sphere\n\n5 1 1 2 3.5 1 1 1 0 0\n2 1 1 2 0.5 1 1 0 0 -1\n";
    std::fs::write(&path, lammps).unwrap();
    let scene = read_data_file(&path, [true; 3], ff, 1).unwrap();
    assert_eq!(scene.particles.ids.as_deref(), Some(&[2, 5][..]));
    assert_eq!(
        scene.particles.positions,
        vec![[0.5, 1.0, -3.0], [7.5, 1.0, 1.0]]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `read_data_file` used to rebuild the force field of a sphere file from
/// the material alone (`ForceField::dem(material)`), dropping the skin,
/// gravity and multi-contact closure the caller had set.
#[test]
fn a_sphere_file_keeps_the_callers_skin_gravity_and_closure() {
    let dir = common::scratch_dir("datafile-ff");
    let path = dir.join("input.data");
    std::fs::write(&path, LIGGGHTS_DATA).unwrap();
    let mut ff = ForceField::dem(sphere_material());
    ff.skin = 0.004;
    ff.gravity = Some([0.0, 0.0, -9.81]);
    ff.multicontact = Some(serde_json::from_value(json!({"prefactor": 0.5})).unwrap());
    let scene = read_data_file(&path, [false; 3], ff.clone(), 1).unwrap();
    assert_eq!(scene.force_field, ff);
    // The file decides the model: bonded-model terms go, the rest stays.
    let mut bpm_ff = ForceField::paper(-0.5);
    bpm_ff.granular = ff.granular;
    bpm_ff.skin = 0.004;
    bpm_ff.gravity = ff.gravity;
    let scene = read_data_file(&path, [false; 3], bpm_ff, 1).unwrap();
    assert!(scene.force_field.bond.is_zero() && scene.force_field.pair.is_none());
    assert_eq!(scene.force_field.skin, 0.004);
    assert_eq!(scene.force_field.gravity, Some([0.0, 0.0, -9.81]));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn what_a_scene_cannot_hold_is_refused_with_the_reason() {
    let dir = common::scratch_dir("datafile-refused");
    let path = dir.join("refused.data");
    let read = |text: &str| {
        std::fs::write(&path, text).unwrap();
        read_data_file(&path, [true; 3], ForceField::paper(0.0), 1)
    };
    let cases: [(&str, &str, usize, &[&str]); 9] = [
        // Per-type coefficients that differ: one material per scene.
        (
            "2 1 1 50 1",
            "2 1 1.5 50 1",
            21,
            &["Pair Coeffs", "differ between types (1 and 2)"],
        ),
        (
            "1 1 -0.5 1\n",
            "1 1 -0.5 1\n2 1 0 1\n",
            26,
            &["Bond Coeffs", "differ"],
        ),
        (
            "Pair Coeffs # bpm/contact\n\n1 1 1 50 1\n2 1 1 50 1",
            "PairIJ Coeffs\n\n1 1 1 1 50 1\n1 2 1 1 50 1\n2 2 1 2 50 1",
            22,
            &["PairIJ Coeffs", "(1 1 and 2 2)"],
        ),
        // Many-body sections and bodies.
        (
            "\nBonds\n",
            "\nAngles\n\n1 1 17 4 2\n\nBonds\n",
            43,
            &["`Angles`", "no angles"],
        ),
        (
            "\nBonds\n",
            "\nDihedrals\n\n1 1 17 4 2 9\n\nBonds\n",
            43,
            &["no dihedrals"],
        ),
        (
            "\nBonds\n",
            "\nImpropers\n\n1 1 17 4 2 9\n\nBonds\n",
            43,
            &["no impropers"],
        ),
        // Duplicate and non-positive ids, unknown sections.
        (
            "30 8 1 5 5.9 1 0 0 0",
            "9 8 1 5 5.9 1 0 0 0",
            0,
            &["atom id 9 appears twice"],
        ),
        (
            "17 3 1 9.6 5 0 0 0 0",
            "0 3 1 9.6 5 0 0 0 0",
            29,
            &["atom id 0", "count from 1"],
        ),
        (
            "\nAtoms # bond\n",
            "\nGrains\n\n1 2 3\n\nAtoms # bond\n",
            27,
            &["unknown section `Grains`"],
        ),
    ];
    for (from, to, line, words) in cases {
        assert!(WRITE_DATA.contains(from), "{from}");
        let err = read(&WRITE_DATA.replacen(from, to, 1))
            .unwrap_err()
            .to_string();
        for w in words {
            assert!(err.contains(w), "{to}: {err}");
        }
        if line > 0 {
            assert!(err.contains(&format!("line {line}:")), "{to}: {err}");
        }
    }
    // Coefficients equal as numbers are one material, however written.
    read(&WRITE_DATA.replacen("2 1 1 50 1", "2 1.0 1 5e1 1.", 1)).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_data_files_name_the_line() {
    let dir = common::scratch_dir("datafile-bad");
    let cases = [
        ("9 8 1 5 5 1 0 0 0", "9 8 1 5 x 1 0 0 0", 31, "`x`"),
        ("3 1 2 4", "3 1 2 44", 47, "not in Atoms"),
        ("5 atoms", "6 atoms", 0, "header says 6 atoms"),
        ("0 10 ylo yhi", "10 0 ylo yhi", 0, "ylo yhi"),
        ("2 2.5", "2 -2.5", 16, "positive"),
        ("9 8 1 5 5 1 0 0 0", "9 8 1 5 5", 31, "id mol type x y z"),
    ];
    for (from, to, line, words) in cases {
        assert!(WRITE_DATA.contains(from), "{from}");
        let path = dir.join("bad.data");
        std::fs::write(&path, WRITE_DATA.replacen(from, to, 1)).unwrap();
        let err = read_data_file(&path, [true; 3], ForceField::paper(0.0), 1)
            .unwrap_err()
            .to_string();
        assert!(err.contains(words), "{to}: {err}");
        if line > 0 {
            assert!(err.contains(&format!("line {line}:")), "{to}: {err}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
