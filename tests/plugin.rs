//! The LAMMPS plugin (Debian's LAMMPS + our styles, `lmp-bpm`) against the
//! native engine on identical configurations, under MPI and newton on/off;
//! restart files; errors on bad input.

mod common;

use bpm::scene::Scene;
use bpm::verify::tolerances::tolerance;
use bpm::verify::{
    contact_solid, lammps_single_point, max_relative_deviation, native_single_point, run_lmp_bpm,
    single_point::read_dump, SinglePoint,
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

/// `lammps` equals `native` within the step-0 entries of the tolerance
/// table: forces and pressure tensor relative to their largest component,
/// each energy relative to itself.
fn assert_step_zero_agrees(lammps: &SinglePoint, native: &SinglePoint, case: &str) {
    let dev = max_relative_deviation(&lammps.forces, &native.forces);
    assert!(
        dev <= tolerance("step-0 forces"),
        "{case}: max force deviation {dev:e}"
    );
    let dev = max_relative_deviation(&[lammps.pressure], &[native.pressure]);
    assert!(
        dev <= tolerance("step-0 stress"),
        "{case}: pressure deviation {dev:e}: {:?} vs {:?}",
        lammps.pressure,
        native.pressure
    );
    for k in 0..2 {
        let dev = max_relative_deviation(&[[lammps.energies[k]]], &[[native.energies[k]]]);
        assert!(
            dev <= tolerance("step-0 energies"),
            "{case}: energy {k} deviation {dev:e}: {:?} vs {:?}",
            lammps.energies,
            native.energies
        );
    }
}

#[test]
fn plugin_forces_and_pressure_equal_the_native_engine() {
    for a_b in [0.0, -0.5, 1.0] {
        let s = scene(a_b);
        let native = native_single_point(&s);
        assert!(
            native.energies[0] > 0.0 && native.energies[1] > 0.0,
            "the scene must have stretched bonds and pair contacts"
        );
        let lmp =
            lammps_single_point(lmp(), &s, true, 1, &workdir(), &format!("np1-{a_b}")).unwrap();
        assert_step_zero_agrees(&lmp, &native, &format!("a_B = {a_b}"));
    }
}

/// `s` through LAMMPS on each `(ranks, newton)` equals the native engine
/// at step 0; `tag` names the runs.
fn assert_ranks_agree(s: &Scene, runs: &[(usize, bool)], tag: &str) {
    let native = native_single_point(s);
    for &(ranks, newton) in runs {
        let lmp = lammps_single_point(
            lmp(),
            s,
            newton,
            ranks,
            &workdir(),
            &format!("{tag}-{ranks}-{newton}"),
        )
        .unwrap();
        assert_step_zero_agrees(
            &lmp,
            &native,
            &format!("{tag}, np {ranks}, newton {newton}"),
        );
    }
}

#[test]
fn one_and_two_ranks_agree_with_newton_on_and_off() {
    assert_ranks_agree(&scene(-0.5), &[(1, false), (2, true), (2, false)], "mpi");
}

#[test]
fn the_zero_net_variant_in_the_plugin_equals_the_native_engine_on_ranks_and_newton() {
    let mut s = scene(-0.5);
    let plain = native_single_point(&s);
    s.force_field.zero_net_multibody = true;
    let changed = max_relative_deviation(&native_single_point(&s).forces, &plain.forces);
    assert!(
        changed > 1e-3,
        "the variant must change the forces: {changed:e}"
    );
    assert_ranks_agree(&s, &[(1, true), (2, true), (2, false)], "zero-net");
}

#[test]
fn a_restart_keeps_every_bond_reference_length_and_the_zero_net_setting() {
    for zero_net in [false, true] {
        restart_resumes_the_run(zero_net);
    }
}

/// A run written to a restart file halfway and resumed from it (the
/// restart carries the style's settings; `restart_read.in` sets none)
/// ends where the run without a restart ends.
fn restart_resumes_the_run(zero_net: bool) {
    let mut s = scene(-0.5);
    s.force_field.zero_net_multibody = zero_net;
    let dir = workdir();
    let restart = dir.join(format!("state-{zero_net}.restart"));
    let continuous = dir.join(format!("continuous-{zero_net}.dump"));
    let resumed = dir.join(format!("resumed-{zero_net}.dump"));
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
    // Columns x y z fx fy fz (restart_*.in).
    let cols = |rows: &[Vec<f64>], from: usize| -> Vec<[f64; 3]> {
        rows.iter()
            .map(|r| [r[from], r[from + 1], r[from + 2]])
            .collect()
    };
    let dx = cols(&a, 0)
        .iter()
        .zip(&cols(&b, 0))
        .map(|(p, q)| common::dist(p, q))
        .fold(0.0, bpm::verify::single_point::nan_max);
    let df = max_relative_deviation(&cols(&b, 3), &cols(&a, 3));
    assert!(
        dx <= tolerance("restart positions") && df <= tolerance("restart forces"),
        "zero net {zero_net}: after restart, positions differ by {dx:e} d, forces by {df:e}"
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

#[test]
fn a_blow_up_stops_lammps_naming_the_step_the_atoms_and_the_timestep() {
    // rms speed 0.03 (T = m v^2 / 3 per component in LJ units) at five
    // times the paper's timestep: past the stable limit, about 0.19 tau at
    // this scene's a_B = -0.5 (results/stability).
    let tail = "velocity all create 0.0003 7 mom yes\nfix 1 all nve\ntimestep 0.5\nrun 2000\n";
    let err = error_of_edited_setup("blow_up", &[], tail);
    for words in [
        "bond_style bpm/multibody: simulation became unstable at step",
        "atoms with IDs",
        "Likely cause: the timestep dt = 0.5 tau is near or above",
    ] {
        assert!(err.contains(words), "`{words}` missing from:\n{err}");
    }
    assert!(
        !err.contains("Segmentation") && !err.contains("panicked"),
        "{err}"
    );
    eprintln!("{err}");
}
