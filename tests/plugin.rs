//! The LAMMPS plugin (Debian's LAMMPS + our styles, `lmp-bpm`) against the
//! native engine on identical configurations, under MPI and newton on/off;
//! restart files; errors on bad input.

mod common;

use bpm::scene::Scene;
use bpm::verify::{
    contact_solid, lammps_single_point, max_relative_deviation, native_single_point, run_lmp_bpm,
    single_point::read_dump,
};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

fn lmp() -> &'static Path {
    Path::new(env!("CARGO_BIN_EXE_lmp-bpm"))
}

fn workdir() -> PathBuf {
    common::scratch_dir("plugin")
}

/// The built-in contact solid (L = 6 d), built once per test binary.
fn scene(a_b: f64) -> Scene {
    static BASE: OnceLock<Scene> = OnceLock::new();
    let mut s = BASE
        .get_or_init(|| contact_solid(6.0, 5, 0.0).unwrap())
        .clone();
    s.force_field = bpm::scene::ForceField::paper(a_b);
    s
}

fn pressure_ok(a: &[f64; 6], b: &[f64; 6], tol: f64) -> bool {
    let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    a.iter().zip(b).all(|(x, y)| (x - y).abs() < tol * scale)
}

#[test]
fn plugin_forces_and_pressure_equal_the_native_engine() {
    for a_b in [0.0, -0.5, 1.0] {
        let s = scene(a_b);
        let native = native_single_point(&s);
        assert!(
            native.energies[1] > 0.0,
            "the scene must have pair contacts"
        );
        let lmp =
            lammps_single_point(lmp(), &s, true, 1, &workdir(), &format!("np1-{a_b}")).unwrap();
        let dev = max_relative_deviation(&lmp.forces, &native.forces);
        assert!(dev < 1e-12, "a_B = {a_b}: max force deviation {dev:e}");
        assert!(
            pressure_ok(&lmp.pressure, &native.pressure, 1e-12),
            "a_B = {a_b}: {:?} vs {:?}",
            lmp.pressure,
            native.pressure
        );
        for k in 0..2 {
            assert!(
                (lmp.energies[k] - native.energies[k]).abs() < 1e-12 * native.energies[k].abs()
            );
        }
    }
}

#[test]
fn one_and_two_ranks_agree_with_newton_on_and_off() {
    let s = scene(-0.5);
    let native = native_single_point(&s);
    for (ranks, newton) in [(1, false), (2, true), (2, false)] {
        let lmp = lammps_single_point(
            lmp(),
            &s,
            newton,
            ranks,
            &workdir(),
            &format!("mpi-{ranks}-{newton}"),
        )
        .unwrap();
        let dev = max_relative_deviation(&lmp.forces, &native.forces);
        assert!(
            dev < 1e-10,
            "np {ranks}, newton {newton}: max force deviation {dev:e}"
        );
        assert!(
            pressure_ok(&lmp.pressure, &native.pressure, 1e-10),
            "np {ranks}, newton {newton}"
        );
    }
}

#[test]
fn a_restart_keeps_every_bond_reference_length() {
    let s = scene(-0.5);
    let dir = workdir();
    let restart = dir.join("state.restart");
    let continuous = dir.join("continuous.dump");
    let resumed = dir.join("resumed.dump");
    let var = |dump: &Path| {
        [
            ("restart", restart.display().to_string()),
            ("dump", dump.display().to_string()),
        ]
    };
    run_lmp_bpm(
        lmp(),
        &s,
        "restart_write.in",
        true,
        1,
        &dir,
        "restart",
        &var(&continuous),
        200,
    )
    .unwrap();
    run_lmp_bpm(
        lmp(),
        &s,
        "restart_read.in",
        true,
        1,
        &dir,
        "restart",
        &var(&resumed),
        100,
    )
    .unwrap();
    let a = read_dump(&continuous).unwrap();
    let b = read_dump(&resumed).unwrap();
    assert_eq!(a.len(), b.len());
    let fscale = a
        .iter()
        .flat_map(|r| r[3..6].iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let (mut dx, mut df) = (0.0f64, 0.0f64);
    for (p, q) in a.iter().zip(&b) {
        for k in 0..3 {
            dx = dx.max((p[k] - q[k]).abs());
            df = df.max((p[k + 3] - q[k + 3]).abs());
        }
    }
    assert!(
        dx < 1e-10 && df < 1e-10 * fscale,
        "after restart: positions differ by {dx:e}, forces by {df:e}"
    );
}

/// Runs `setup.in` with `replace` applied plus `tail`; returns the error text.
fn error_of_edited_setup(tag: &str, replace: &[(&str, &str)], tail: &str) -> String {
    let mut text = bpm::lammps::templates::template("setup.in")
        .unwrap()
        .to_string();
    for (from, to) in replace {
        assert!(text.contains(from), "setup.in has no `{from}`");
        text = text.replace(from, to);
    }
    text.push_str(tail);
    let script = workdir().join(format!("{tag}.in"));
    std::fs::write(&script, text).unwrap();
    match run_lmp_bpm(
        lmp(),
        &scene(-0.5),
        script.to_str().unwrap(),
        true,
        1,
        &workdir(),
        tag,
        &[],
        0,
    ) {
        Ok(out) => panic!("{tag}: LAMMPS accepted bad input:\n{out}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_input_gets_a_clear_lammps_error() {
    let bond = "bond_coeff      1 ${kB} ${aB} ${gB}";
    let pair = "pair_coeff      * * ${kP} ${d} ${aP} ${gP}";
    // (name, edits of setup.in, expected words of the error)
    type Case<'a> = (&'a str, Vec<(&'a str, &'a str)>, &'a str);
    let cases: Vec<Case> = vec![
        (
            "count",
            vec![(bond, "bond_coeff 1 1.0 0.0")],
            "takes 4 values",
        ),
        (
            "numeric",
            vec![(bond, "bond_coeff 1 abc 0 1")],
            "Expected floating point",
        ),
        (
            "negative",
            vec![(bond, "bond_coeff 1 -1 0 1")],
            "k_B must be >= 0",
        ),
        (
            "pair_count",
            vec![(pair, "pair_coeff 1 1 1 1 50")],
            "takes 6 values",
        ),
        (
            "d_zero",
            vec![(pair, "pair_coeff 1 1 1 0 50 1")],
            "d must be > 0",
        ),
        ("no_bond_coeff", vec![(bond, "")], "oeffs are not set"),
        ("no_pair_coeff", vec![(pair, "")], "oeffs are not set"),
        (
            "ghost_velocity",
            vec![(
                "comm_modify     vel yes cutoff ${commcut}",
                "comm_modify cutoff ${commcut}",
            )],
            "comm_modify vel yes",
        ),
        (
            "special",
            vec![("special_bonds   lj 0 1 1", "special_bonds lj 1 1 1")],
            "special_bonds lj 0 1 1",
        ),
        (
            "short_comm",
            vec![("cutoff ${commcut}", "cutoff 1.0")],
            "exceeds the communication cutoff",
        ),
    ];
    for (tag, replace, expected) in cases {
        let err = error_of_edited_setup(tag, &replace, "run 0\n");
        assert!(
            err.contains(expected),
            "{tag}: expected `{expected}` in:\n{err}"
        );
        assert!(
            !err.contains("Segmentation") && !err.contains("panicked"),
            "{tag}: crashed:\n{err}"
        );
    }
}

#[test]
fn an_atom_style_without_bonds_is_refused() {
    let script = workdir().join("atomic.in");
    std::fs::write(
        &script,
        "units lj\natom_style atomic\nregion b block 0 5 0 5 0 5\ncreate_box 1 b\nbond_style bpm/multibody\n",
    )
    .unwrap();
    let out = Command::new("timeout")
        .args(["60", env!("CARGO_BIN_EXE_lmp-bpm"), "-in"])
        .arg(&script)
        .args(["-log", "none"])
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!out.status.success(), "{text}");
    assert!(text.contains("bonds"), "{text}");
}
