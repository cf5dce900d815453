//! LAMMPS data files in and out: a file as LAMMPS's write_data makes it
//! (coefficient sections, unsorted and non-contiguous ids, image flags)
//! imports, exports and imports again to the same scene; malformed files
//! name the line.

mod common;

use bpm::scene::datafile::{read_data_file, write_data_file};
use bpm::scene::{ForceField, Mass};

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
