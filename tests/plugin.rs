//! The LAMMPS plugin (Debian's LAMMPS + our styles, `lmp-bpm`) against the
//! native engine on identical configurations, under MPI and newton on/off.

mod common;

use bpm::engine::StageDrivers;
use bpm::lammps::{write_data_file, write_reference_lengths, ScriptVars};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::{build_system, ForceField, Scene, StageSpec};
use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

fn workdir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("bpm-plugin-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small strained, moving bulk solid with two grains' worth of contacts:
/// bonds carry force, velocities exercise damping, and removing the bonds
/// of a slab creates non-bonded overlaps for the pair style.
fn test_scene(a_b: f64) -> Scene {
    static BASE: OnceLock<Scene> = OnceLock::new();
    let base = BASE.get_or_init(|| {
        let mut p = BulkParams::paper(6.0, 5, 0.0);
        p.relax_time = 20.0;
        p.thermal_time = 50.0;
        p.quench_time = 100.0;
        build_bulk(&p, 1, false).unwrap().0
    });
    let mut s = base.clone();
    s.force_field = ForceField::paper(a_b);
    let squeeze = 0.985;
    for (i, x) in s.particles.positions.iter_mut().enumerate() {
        for (d, c) in x.iter_mut().enumerate() {
            *c = *c * squeeze + 1e-3 * (((i * 7 + d * 3) % 11) as f64 - 5.0);
        }
    }
    s.simbox.lengths = s.simbox.lengths.map(|l| l * squeeze);
    s.particles.velocities = Some(common::random_rows(s.particles.positions.len(), 0.05, 77));
    // Cut the bonds crossing the plane z = 3: the two halves touch through
    // pair contacts only (a "grain with surface contacts").
    let z = &s.particles.positions;
    let keep: Vec<usize> = (0..s.bonds.pairs.len())
        .filter(|&k| {
            let [i, j] = s.bonds.pairs[k];
            (z[i][2] < 3.0 * squeeze) == (z[j][2] < 3.0 * squeeze)
        })
        .collect();
    let r0 = s.bonds.r0.clone().unwrap();
    s.bonds.pairs = keep.iter().map(|&k| s.bonds.pairs[k]).collect();
    s.bonds.r0 = Some(keep.iter().map(|&k| r0[k]).collect());
    s.stages = vec![StageSpec::hold("point", 0, 0.1)];
    s
}

struct LammpsResult {
    forces: Vec<[f64; 3]>,
    pressure: [f64; 6],
    energies: [f64; 2],
}

/// Runs `lmp-bpm` on template `input` for `scene`; returns the status and
/// the output. `extra` adds `-var name value` pairs.
fn lmp_bpm(
    scene: &Scene,
    input: &str,
    newton: bool,
    ranks: usize,
    tag: &str,
    extra: &[(&str, String)],
) -> (bool, String) {
    let dir = workdir();
    let data = dir.join(format!("{tag}.data"));
    std::fs::write(&data, write_data_file(scene)).unwrap();
    std::fs::write(
        format!("{}.r0", data.display()),
        write_reference_lengths(scene),
    )
    .unwrap();
    let vars = ScriptVars::of(scene, data.to_str().unwrap(), newton);
    let input = if input.starts_with('/') {
        input.to_string()
    } else {
        format!("{}/lammps_inputs/{input}", env!("CARGO_MANIFEST_DIR"))
    };
    // A hung LAMMPS (e.g. NaN positions) must fail the test, not stall CI.
    let mut cmd = Command::new("timeout");
    cmd.arg("120");
    if ranks > 1 {
        cmd.args([
            "mpirun.openmpi",
            "--allow-run-as-root",
            "--oversubscribe",
            "--bind-to",
            "none",
        ]);
        cmd.args(["-np", &ranks.to_string()]);
    }
    cmd.arg(env!("CARGO_BIN_EXE_lmp-bpm"));
    cmd.args(["-in", &input, "-log", "none"]);
    cmd.args(vars.args());
    for (k, v) in extra {
        cmd.args(["-var", k, v]);
    }
    cmd.env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
    let out = cmd.output().expect("run lmp-bpm");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

/// Rows of a LAMMPS custom dump sorted by id, without the id column.
fn read_dump(path: &std::path::Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip_while(|l| !l.starts_with("ITEM: ATOMS"))
        .skip(1)
        .map(|line| {
            line.split_whitespace()
                .skip(1)
                .map(|t| t.parse().unwrap())
                .collect()
        })
        .collect()
}

fn run_lammps(scene: &Scene, newton: bool, ranks: usize, tag: &str) -> LammpsResult {
    let dump = workdir().join(format!("{tag}.dump"));
    let (ok, stdout) = lmp_bpm(
        scene,
        "single_point.in",
        newton,
        ranks,
        tag,
        &[("dump", dump.display().to_string())],
    );
    assert!(ok, "lmp-bpm failed:\n{stdout}");
    let numbers = |key: &str| -> Vec<f64> {
        let line = stdout
            .lines()
            .find(|l| l.starts_with(key))
            .unwrap_or_else(|| panic!("no {key} in\n{stdout}"));
        line.split_whitespace()
            .skip(1)
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let p = numbers("BPM_PRESSURE");
    let e = numbers("BPM_ENERGY");
    let forces: Vec<[f64; 3]> = read_dump(&dump)
        .iter()
        .map(|v| [v[0], v[1], v[2]])
        .collect();
    assert_eq!(forces.len(), scene.particles.positions.len());
    LammpsResult {
        forces,
        pressure: [p[0], p[1], p[2], p[3], p[4], p[5]],
        energies: [e[0], e[1]],
    }
}

struct Native {
    forces: Vec<[f64; 3]>,
    pressure: [f64; 6],
    energies: [f64; 2],
}

fn run_native(scene: &Scene) -> Native {
    let mut sys = build_system(scene, 1);
    sys.setup(&StageDrivers {
        dt: 0.1,
        ..Default::default()
    });
    Native {
        forces: sys.f.clone(),
        pressure: sys.pressure_tensor(),
        energies: [
            sys.report.interactions.bonds.energy,
            sys.report.interactions.pairs.energy,
        ],
    }
}

fn max_rel_force_dev(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let scale = common::max_abs(b);
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |d| (p[d] - q[d]).abs()))
        .fold(0.0, f64::max)
        / scale
}

#[test]
fn plugin_forces_and_pressure_equal_the_native_engine() {
    for a_b in [0.0, -0.5, 1.0] {
        let scene = test_scene(a_b);
        let native = run_native(&scene);
        assert!(
            native.energies[1] > 0.0,
            "the scene must have pair contacts"
        );
        let lmp = run_lammps(&scene, true, 1, &format!("np1-{a_b}"));
        let dev = max_rel_force_dev(&lmp.forces, &native.forces);
        assert!(dev < 1e-12, "a_B = {a_b}: max force deviation {dev:e}");
        let pscale = native.pressure.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..6 {
            assert!(
                (lmp.pressure[k] - native.pressure[k]).abs() < 1e-12 * pscale,
                "a_B = {a_b}: P[{k}] {} vs {}",
                lmp.pressure[k],
                native.pressure[k]
            );
        }
        for k in 0..2 {
            assert!(
                (lmp.energies[k] - native.energies[k]).abs()
                    < 1e-12 * native.energies[k].abs().max(1e-300)
            );
        }
    }
}

#[test]
fn one_and_two_ranks_agree_with_newton_on_and_off() {
    let scene = test_scene(-0.5);
    let native = run_native(&scene);
    for (ranks, newton) in [(1, false), (2, true), (2, false)] {
        let lmp = run_lammps(&scene, newton, ranks, &format!("mpi-{ranks}-{newton}"));
        let dev = max_rel_force_dev(&lmp.forces, &native.forces);
        assert!(
            dev < 1e-10,
            "np {ranks}, newton {newton}: max force deviation {dev:e}"
        );
        let pscale = native.pressure.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..6 {
            assert!(
                (lmp.pressure[k] - native.pressure[k]).abs() < 1e-10 * pscale,
                "np {ranks}, newton {newton}: P[{k}]"
            );
        }
    }
}

#[test]
fn a_restart_keeps_every_bond_reference_length() {
    let scene = test_scene(-0.5);
    let dir = workdir();
    let restart = dir.join("state.restart");
    let continuous = dir.join("continuous.dump");
    let resumed = dir.join("resumed.dump");
    let (ok, out) = lmp_bpm(
        &scene,
        "restart_write.in",
        true,
        1,
        "restart",
        &[
            ("restart", restart.display().to_string()),
            ("dump", continuous.display().to_string()),
        ],
    );
    assert!(ok, "{out}");
    let (ok, out) = lmp_bpm(
        &scene,
        "restart_read.in",
        true,
        1,
        "restart",
        &[
            ("restart", restart.display().to_string()),
            ("dump", resumed.display().to_string()),
        ],
    );
    assert!(ok, "{out}");
    let a = read_dump(&continuous);
    let b = read_dump(&resumed);
    assert_eq!(a.len(), b.len());
    let fscale = a
        .iter()
        .flat_map(|r| r[3..6].iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    let mut dx = 0.0f64;
    let mut df = 0.0f64;
    for (p, q) in a.iter().zip(&b) {
        for k in 0..3 {
            dx = dx.max((p[k] - q[k]).abs());
            df = df.max((p[k + 3] - q[k + 3]).abs());
        }
    }
    assert!(
        dx < 1e-10 && df < 1e-10 * fscale,
        "after restart: positions differ by {dx:e}, forces by {df:e} (scale {fscale:e})"
    );
}

/// Runs a script made of `setup.in` with `replace` applied, and returns the
/// status and output of `lmp-bpm`.
fn run_edited_setup(tag: &str, replace: &[(&str, &str)], tail: &str) -> (bool, String) {
    let setup = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/lammps_inputs/setup.in"
    ))
    .unwrap();
    let mut text = setup;
    for (from, to) in replace {
        assert!(text.contains(from), "setup.in has no `{from}`");
        text = text.replace(from, to);
    }
    text.push_str(tail);
    let script = workdir().join(format!("{tag}.in"));
    std::fs::write(&script, text).unwrap();
    let scene = test_scene(-0.5);
    lmp_bpm(&scene, script.to_str().unwrap(), true, 1, tag, &[])
}

#[test]
fn bad_input_gets_a_clear_lammps_error() {
    let bond = "bond_coeff      1 ${kB} ${aB} ${gB}";
    let pair = "pair_coeff      1 1 ${kP} ${d} ${aP} ${gP}";
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
        let (ok, out) = run_edited_setup(tag, &replace, "run 0\n");
        assert!(!ok, "{tag}: LAMMPS accepted bad input:\n{out}");
        assert!(
            out.contains(expected),
            "{tag}: expected `{expected}` in:\n{out}"
        );
        assert!(
            !out.contains("Segmentation") && !out.contains("panicked"),
            "{tag}: crashed:\n{out}"
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
