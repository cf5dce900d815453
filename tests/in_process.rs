//! LAMMPS opened in this process through the bindgen bindings of
//! `library.h`, with our styles registered by `bpm_register_styles`.

mod common;

use bpm::engine::StageDrivers;
use bpm::lammps::{
    write_reference_lengths, write_run_data_file, write_templates, Lammps, ScriptVars,
};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::{build_system, ForceField};
use bpm::verify::max_relative_deviation;
use bpm::verify::tolerances::tolerance;

#[test]
fn in_process_lammps_gives_the_native_forces() {
    let mut scene = build_bulk(&BulkParams::shortened(5.0, 8, 0.0), 1, false)
        .unwrap()
        .0;
    scene.force_field = ForceField::paper(-0.5);
    for x in &mut scene.particles.positions {
        *x = x.map(|c| c * 0.99);
    }
    scene.simbox.lengths = scene.simbox.lengths.map(|l| l * 0.99);
    let dir = common::scratch_dir("inproc");
    let data = dir.join("s.data");
    std::fs::write(&data, write_run_data_file(&scene)).unwrap();
    std::fs::write(
        format!("{}.r0", data.display()),
        write_reference_lengths(&scene),
    )
    .unwrap();
    let inputs = write_templates(&dir).unwrap();
    let vars = ScriptVars::of(&scene, data.to_str().unwrap(), true, &inputs);
    let mut lmp = Lammps::open(&["-log", "none", "-screen", "none"]).unwrap();
    let mut script = String::new();
    for (k, v) in &vars.vars {
        script.push_str(&format!("variable {k} string \"{v}\"\n"));
    }
    script.push_str("include ${inputs}/setup.in\nthermo_style custom step pe pxx pyy pzz\nrun 0\n");
    lmp.commands(&script).unwrap();
    let forces = lmp.gather_vectors("f").unwrap();

    let mut sys = build_system(&scene, 1);
    sys.setup(&StageDrivers {
        dt: 0.1,
        ..Default::default()
    })
    .unwrap();
    assert!(
        common::max_abs(&sys.particles.f) > 1e-3,
        "the scene must carry forces"
    );
    let dev = max_relative_deviation(&forces, &sys.particles.f);
    assert!(
        dev <= tolerance("step-0 forces"),
        "in-process LAMMPS forces differ by {dev:e}"
    );
    let pxx = lmp.thermo("pxx").unwrap();
    let native_pxx = sys.pressure_tensor()[0];
    let dev = max_relative_deviation(&[[pxx]], &[[native_pxx]]);
    assert!(
        dev <= tolerance("step-0 stress"),
        "pxx {pxx} vs native {native_pxx}"
    );
}
