//! Compiles the LAMMPS shim (`lammps-plugin/*.cpp`) with the `cc` crate
//! against LAMMPS's headers and links LAMMPS and MPI.
//!
//! Defaults are Debian's `liblammps-dev` and Open MPI; `BPM_LAMMPS_INCLUDE`,
//! `BPM_LAMMPS_LIB` and `BPM_MPI_INCLUDE` point at another installation.
//! Without the `lammps` feature (`--no-default-features`) nothing is built
//! or linked: the kernels alone, e.g. as the static library that
//! `scripts/build-modern-plugin.sh` links into a plugin for another LAMMPS.

use std::env;
use std::path::Path;

fn main() {
    if env::var_os("CARGO_FEATURE_LAMMPS").is_none() {
        return;
    }
    let include = env::var("BPM_LAMMPS_INCLUDE").unwrap_or_else(|_| "/usr/include/lammps".into());
    let mpi_include = env::var("BPM_MPI_INCLUDE")
        .unwrap_or_else(|_| "/usr/lib/x86_64-linux-gnu/openmpi/include".into());
    for var in ["BPM_LAMMPS_INCLUDE", "BPM_LAMMPS_LIB", "BPM_MPI_INCLUDE"] {
        println!("cargo:rerun-if-env-changed={var}");
    }
    if !Path::new(&include).join("lammps.h").exists() {
        panic!(
            "LAMMPS headers not found in {include}: run scripts/ensure-deps.sh (Debian's liblammps-dev), \
             or set BPM_LAMMPS_INCLUDE"
        );
    }
    // Every source and header of the shim: the plugin build scripts take
    // the same folder whole.
    let mut shim: Vec<_> = std::fs::read_dir("lammps-plugin")
        .expect("lammps-plugin/ is part of the crate")
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|path| path.extension().is_some_and(|x| x == "cpp" || x == "h"))
        .collect();
    shim.sort();
    let mut build = cc::Build::new();
    build
        .cpp(true)
        .std("c++17")
        .include("lammps-plugin")
        .include(&include)
        .include(&mpi_include)
        .include(format!("{mpi_include}/openmpi"))
        .warnings(false)
        .flag_if_supported("-Wno-unused-parameter");
    println!("cargo:rerun-if-changed=lammps-plugin");
    for path in shim {
        println!("cargo:rerun-if-changed={}", path.display());
        if path.extension().is_some_and(|x| x == "cpp") {
            build.file(path);
        }
    }
    build.compile("bpm_lammps_shim");

    // Rust bindings of LAMMPS's C library interface, for running LAMMPS
    // in-process (src/lammps/sys.rs).
    let header = Path::new(&include).join("library.h");
    println!("cargo:rerun-if-changed={}", header.display());
    let bindings = bindgen::Builder::default()
        .header(header.to_string_lossy())
        .allowlist_function("lammps_.*")
        .generate()
        .unwrap_or_else(|e| {
            panic!(
                "bindgen on {}: {e} (needs Debian's libclang-dev)",
                header.display()
            )
        });
    let out = std::path::PathBuf::from(env::var("OUT_DIR").expect("OUT_DIR"));
    bindings
        .write_to_file(out.join("lammps_library.rs"))
        .expect("writing LAMMPS bindings");
    if let Ok(lib) = env::var("BPM_LAMMPS_LIB") {
        println!("cargo:rustc-link-search=native={lib}");
    }
    println!("cargo:rustc-link-search=native=/usr/lib/x86_64-linux-gnu/openmpi/lib");
    println!("cargo:rustc-link-lib=dylib=lammps");
    println!("cargo:rustc-link-lib=dylib=mpi");
}
