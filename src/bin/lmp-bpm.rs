//! `lmp-bpm`: Debian's LAMMPS with `bond_style bpm/multibody` and
//! `pair_style bpm/contact` registered; takes `lmp`'s command-line options
//! (`-in`, `-var`, `-log`, `-screen`, `-echo`, ...) and runs under `mpirun`.

use std::ffi::{c_char, c_int, CString};

extern "C" {
    fn bpm_lmp_main(argc: c_int, argv: *mut *mut c_char) -> c_int;
}

fn main() {
    // Keep the Rust kernels linked: the shim calls them through the C ABI.
    let _ = bpm::ffi::BPM_OK;
    let args: Vec<CString> = std::env::args()
        .map(|a| CString::new(a).unwrap_or_default())
        .collect();
    let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
    argv.push(std::ptr::null_mut());
    // SAFETY: argv is a null-terminated array of valid C strings that
    // outlive the call.
    let status = unsafe { bpm_lmp_main(args.len() as c_int, argv.as_mut_ptr()) };
    std::process::exit(status);
}
