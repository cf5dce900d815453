//! The C ABI of `pair_style bpm/granular`: DEM sphere contacts with the
//! optional multi-contact closure ([`crate::kernels::GranularList`]).
//!
//! The shim hands over the words of `pair_coeff * *` and gets a handle
//! (the coefficients, parsed and checked here, and the passes' buffers),
//! then per force evaluation calls the corrections pass, copies the
//! correction rows to ghosts, and calls the forces pass. Every failure
//! comes back as a status and a message naming atoms by their IDs.

use super::{
    counts, guard, half_list, list, rows, write_message, BPM_ERR_INDEX, BPM_ERR_NULL,
    BPM_ERR_STOPPED, BPM_OK,
};
use crate::engine::MultiContact;
use crate::kernels::{
    GranularCoeffs, GranularList, GranularMaterial, HalfSpace, Layout, ListAtoms, ListClosure,
    ListWall, MprSwitch, MprTest, NormalDamping, SpringDashpotSlider, Tally, Twisting, WallPlane,
};
use crate::scene::validate::{check_granular, check_multicontact};
use std::ffi::{c_char, CStr};
use std::slice;

/// Contacts per atom a row holds unless `slots` says otherwise: above the
/// 12 to 14 touching neighbours of a dense packing, with room for the
/// pairs within the closure's reach.
pub const DEFAULT_SLOTS: usize = 32;

/// What `pair_coeff * *` of `pair_style bpm/granular` sets.
#[derive(Clone, Debug, PartialEq)]
pub struct GranularStyleCoeffs {
    /// The spheres' material and friction.
    pub material: GranularMaterial,
    /// The closure, if on.
    pub multicontact: Option<MultiContact>,
    /// Contacts per atom row.
    pub slots: usize,
}

/// Parses the words after `pair_coeff * *`:
///
/// ```text
/// hertz/material E e nu damping tsuji|coeff_restitution
///     tangential mindlin NULL x_gt mu_s
///     [rolling sds k_r g_r mu_r] [twisting marshall | twisting sds k g mu]
///     [multicontact gamma [mpr MPR] [switch whole_contact|per_term]
///                         [test signed|magnitude] [reach R]]
///     [slots N]
/// ```
///
/// the spelling of LAMMPS's `pair_style granular` for the material (as
/// the harness writes it), then the closure. Every value is checked as a
/// scene's would be.
pub fn parse_coeffs(words: &[&str]) -> Result<GranularStyleCoeffs, String> {
    parse(words, false)
}

/// Parses the material words of `fix bpm/granular/wall` (after its
/// number, axis, side, position and velocity): those of
/// [`parse_coeffs`] without `multicontact` and `slots`, which are the
/// pair style's. Checked as a scene's wall material would be.
pub fn parse_wall_material(words: &[&str]) -> Result<GranularMaterial, String> {
    parse(words, true).map(|c| c.material)
}

/// [`parse_coeffs`], or with `wall` [`parse_wall_material`].
fn parse(words: &[&str], wall: bool) -> Result<GranularStyleCoeffs, String> {
    let mut w = Words { words, at: 0 };
    w.expect("hertz/material")?;
    let youngs_modulus = w.number("E")?;
    let restitution = w.number("e")?;
    let poisson_ratio = w.number("nu")?;
    w.expect("damping")?;
    let damping = match w.next("the damping model")? {
        "tsuji" => NormalDamping::Tsuji,
        "coeff_restitution" => NormalDamping::CoeffRestitution,
        other => {
            return Err(format!(
                "damping `{other}`: expected tsuji or coeff_restitution"
            ))
        }
    };
    w.expect("tangential")?;
    w.expect("mindlin")?;
    w.expect("NULL")?;
    let tangential_damping = w.number("x_gt")?;
    let sliding_friction = w.number("mu_s")?;
    let mut material = GranularMaterial {
        youngs_modulus,
        poisson_ratio,
        restitution,
        damping,
        tangential_damping,
        sliding_friction,
        rolling: None,
        twisting: Twisting::None,
    };
    let mut multicontact = None;
    let mut slots = DEFAULT_SLOTS;
    let mut seen: Vec<&str> = Vec::new();
    while let Some(word) = w.peek() {
        w.at += 1;
        if seen.contains(&word) {
            return Err(format!("`{word}` is given twice"));
        }
        seen.push(word);
        if wall && word == "keep_history" {
            return Err(
                "`keep_history` goes right after the velocity, before the material words".into(),
            );
        }
        if wall && matches!(word, "multicontact" | "slots") {
            return Err(format!(
                "`{word}` belongs to pair_coeff of pair_style bpm/granular, not to a wall (the closure counts the wall as a contact of its atoms)"
            ));
        }
        match word {
            "rolling" => {
                w.expect("sds")?;
                material.rolling = Some(w.slider("rolling")?);
            }
            "twisting" => {
                material.twisting = match w.next("the twisting model")? {
                    "marshall" => Twisting::Marshall,
                    "sds" => Twisting::Sds(w.slider("twisting")?),
                    other => return Err(format!("twisting `{other}`: expected marshall or sds")),
                }
            }
            "multicontact" => {
                let mut m = MultiContact::standard(w.number("the prefactor gamma")?);
                loop {
                    if let Some(word @ ("mpr" | "switch" | "test" | "reach")) = w.peek() {
                        if seen.contains(&word) {
                            return Err(format!("`{word}` is given twice"));
                        }
                        seen.push(word);
                    }
                    match w.peek() {
                        Some("mpr") => {
                            w.at += 1;
                            m.max_penetration_ratio = Some(w.number("mpr")?);
                        }
                        Some("switch") => {
                            w.at += 1;
                            m.switch = match w.next("the switch")? {
                                "whole_contact" => MprSwitch::WholeContact,
                                "per_term" => MprSwitch::PerTerm,
                                other => {
                                    return Err(format!(
                                        "switch `{other}`: expected whole_contact or per_term"
                                    ))
                                }
                            }
                        }
                        Some("test") => {
                            w.at += 1;
                            m.test = match w.next("the test")? {
                                "signed" => MprTest::Signed,
                                "magnitude" => MprTest::Magnitude,
                                other => {
                                    return Err(format!(
                                        "test `{other}`: expected signed or magnitude"
                                    ))
                                }
                            }
                        }
                        Some("reach") => {
                            w.at += 1;
                            m.reach = w.number("reach")?;
                        }
                        _ => break,
                    }
                }
                multicontact = Some(m);
            }
            "slots" => {
                let n = w.number("slots")?;
                if !((1.0..=4096.0).contains(&n) && n.fract() == 0.0) {
                    return Err(format!(
                        "slots must be a whole number from 1 to 4096, got {n}"
                    ));
                }
                slots = n as usize;
            }
            other => {
                let expected = if wall {
                    "rolling or twisting"
                } else {
                    "rolling, twisting, multicontact or slots"
                };
                return Err(format!("unknown keyword `{other}` (expected {expected})"));
            }
        }
    }
    let context = if wall {
        "fix bpm/granular/wall"
    } else {
        "pair_coeff"
    };
    check_granular(context, &material).map_err(|e| e.to_string())?;
    if let Some(m) = &multicontact {
        check_multicontact("pair_coeff multicontact", m).map_err(|e| e.to_string())?;
    }
    Ok(GranularStyleCoeffs {
        material,
        multicontact,
        slots,
    })
}

/// A cursor over the words of a command.
struct Words<'a> {
    words: &'a [&'a str],
    at: usize,
}

impl<'a> Words<'a> {
    fn peek(&self) -> Option<&'a str> {
        self.words.get(self.at).copied()
    }

    fn next(&mut self, what: &str) -> Result<&'a str, String> {
        let word = self
            .peek()
            .ok_or_else(|| format!("missing {what} at the end"))?;
        self.at += 1;
        Ok(word)
    }

    fn expect(&mut self, keyword: &str) -> Result<(), String> {
        match self.next(&format!("`{keyword}`"))? {
            w if w == keyword => Ok(()),
            w => Err(format!("expected `{keyword}`, got `{w}`")),
        }
    }

    fn number(&mut self, what: &str) -> Result<f64, String> {
        let word = self.next(what)?;
        word.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("{what} must be a finite number, got `{word}`"))
    }

    fn slider(&mut self, what: &str) -> Result<SpringDashpotSlider, String> {
        Ok(SpringDashpotSlider {
            stiffness: self.number(&format!("{what} stiffness"))?,
            damping: self.number(&format!("{what} damping"))?,
            friction: self.number(&format!("{what} friction"))?,
        })
    }
}

/// The state behind a `bpm_granular` handle.
#[derive(Debug)]
pub struct GranularStyle {
    coeffs: GranularStyleCoeffs,
    list: GranularList,
    /// The walls of the current evaluation and whether each is fresh,
    /// kept to reuse their memory.
    walls: Vec<ListWall>,
    fresh: Vec<bool>,
}

impl GranularStyle {
    /// The style of `coeffs`.
    pub fn new(coeffs: GranularStyleCoeffs) -> Self {
        let m = &coeffs.material;
        let closure = coeffs.multicontact.map(|mc| ListClosure {
            closure: mc.closure(),
            half_space: HalfSpace::new(mc.prefactor, m.youngs_modulus, m.poisson_ratio),
            reach: mc.reach,
        });
        let list = GranularList::new(GranularCoeffs::of(m), closure, coeffs.slots);
        Self {
            coeffs,
            list,
            walls: Vec::new(),
            fresh: Vec::new(),
        }
    }
}

/// The `nwords` C strings of `words`, copied.
///
/// # Safety
/// `words` is null or holds `nwords` pointers, each null or to a
/// NUL-terminated string.
unsafe fn owned_words(nwords: i32, words: *const *const c_char) -> Result<Vec<String>, String> {
    if nwords < 0 || (nwords > 0 && words.is_null()) {
        return Err("no words given".to_string());
    }
    let mut owned = Vec::with_capacity(nwords as usize);
    for k in 0..nwords as usize {
        let p = *words.add(k);
        if p.is_null() {
            return Err(format!("word {k} is null"));
        }
        owned.push(CStr::from_ptr(p).to_string_lossy().into_owned());
    }
    Ok(owned)
}

/// Parses the `nwords` words of `pair_coeff * *` ([`parse_coeffs`]) into
/// a new handle; on bad input returns null and writes why to `message`.
///
/// # Safety
/// `words` holds `nwords` NUL-terminated strings; `message` `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_create(
    nwords: i32,
    words: *const *const c_char,
    message: *mut c_char,
    len: i64,
) -> *mut GranularStyle {
    parsed_handle(nwords, words, message, len, |w| {
        parse_coeffs(w).map(GranularStyle::new)
    })
}

/// A boxed handle of what `parse` makes of the `nwords` C strings, or null
/// with why (or that the kernels panicked) written to `message`.
///
/// # Safety
/// As [`owned_words`]; `message` `len` bytes.
unsafe fn parsed_handle<T>(
    nwords: i32,
    words: *const *const c_char,
    message: *mut c_char,
    len: i64,
    parse: impl Fn(&[&str]) -> Result<T, String> + std::panic::UnwindSafe,
) -> *mut T {
    let parsed = std::panic::catch_unwind(move || {
        let owned = owned_words(nwords, words)?;
        let refs: Vec<&str> = owned.iter().map(String::as_str).collect();
        parse(&refs)
    });
    match parsed {
        Ok(Ok(made)) => Box::into_raw(Box::new(made)),
        Ok(Err(reason)) => {
            write_message(&reason, message, len);
            std::ptr::null_mut()
        }
        Err(_) => {
            write_message("internal error in the kernels (a bug)", message, len);
            std::ptr::null_mut()
        }
    }
}

/// Frees a handle (null: nothing).
///
/// # Safety
/// `style` is null or from [`bpm_granular_create`], not freed before.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_destroy(style: *mut GranularStyle) {
    if !style.is_null() {
        drop(Box::from_raw(style));
    }
}

/// Contacts per atom row: rows of the contact memory hold `1 + 9 slots`
/// doubles, rows of the corrections `1 + 2 slots`. 0 for a null handle.
///
/// # Safety
/// `style` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_slots(style: *const GranularStyle) -> i64 {
    style.as_ref().map_or(0, |s| s.coeffs.slots as i64)
}

/// The pair cutoff for spheres up to `max_radius`: `2 max_radius (1 +
/// reach)` with the closure (pairs within its reach receive corrections),
/// else `2 max_radius`. A negative value for a null handle.
///
/// # Safety
/// `style` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_cutoff(style: *const GranularStyle, max_radius: f64) -> f64 {
    style.as_ref().map_or(-1.0, |s| {
        let reach = s.coeffs.multicontact.map_or(0.0, |m| m.reach);
        2.0 * max_radius * (1.0 + reach)
    })
}

/// Whether the closure is on (then the corrections pass and the copy of
/// its rows to ghosts are needed).
///
/// # Safety
/// `style` is null or a live handle.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_has_closure(style: *const GranularStyle) -> i32 {
    style
        .as_ref()
        .is_some_and(|s| s.coeffs.multicontact.is_some()) as i32
}

/// Checks that the box's periodic faces are more than twice the
/// neighbour-list range `range` (the pair cutoff plus the skin) apart
/// (`h`: LAMMPS's shape matrix `[xprd, yprd, zprd, yz, xz, xy]`;
/// `periodic`: 3 flags). Closer faces would let the list hold two images
/// of one partner, one touching and one apart, which share a contact row
/// by ID. (The native engine, which takes the nearest image, needs only
/// twice the cutoff.) Writes why to `message` and returns BPM_ERR_STOPPED
/// if not.
///
/// # Safety
/// `h` 6 doubles, `periodic` 3 ints; `message` `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_check_box(
    range: f64,
    h: *const f64,
    periodic: *const i32,
    step: i64,
    message: *mut c_char,
    len: i64,
) -> i32 {
    guard(|| {
        if h.is_null() || periodic.is_null() {
            return BPM_ERR_NULL;
        }
        let faces = face_distances(list(h, 6));
        let periodic = list(periodic, 3);
        // A NaN range or face fails the check too.
        let clear = |d: usize| range < 0.5 * faces[d];
        match (0..3).find(|&d| periodic[d] != 0 && !clear(d)) {
            None => BPM_OK,
            Some(d) => {
                let text = format!(
                    "at step {step} the box's periodic faces normal to dimension {d} are {:.4} apart, no more than twice the neighbour-list range {range:.4} (the pair cutoff with the closure's reach, plus the skin): the list could hold two images of one partner. Use more atoms (a larger box), a smaller skin, or compress or shear less",
                    faces[d]
                );
                write_message(&text, message, len);
                BPM_ERR_STOPPED
            }
        }
    })
}

/// The distances between opposite faces of a LAMMPS box with shape matrix
/// `h = [xprd, yprd, zprd, yz, xz, xy]` (edge vectors `a = (xprd, 0, 0)`,
/// `b = (xy, yprd, 0)`, `c = (xz, yz, zprd)`): the volume over each face's
/// area.
fn face_distances(h: &[f64]) -> [f64; 3] {
    let (a, b, c) = ([h[0], 0.0, 0.0], [h[5], h[1], 0.0], [h[4], h[3], h[2]]);
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let norm = |u: [f64; 3]| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt();
    let volume = h[0] * h[1] * h[2];
    [
        volume / norm(cross(b, c)),
        volume / norm(cross(c, a)),
        volume / norm(cross(a, b)),
    ]
}

/// The per-atom arrays of a pass: `nall` atoms, the first `nlocal` owned.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RawAtoms {
    x: *const f64,
    v: *const f64,
    omega: *const f64,
    radius: *const f64,
    rmass: *const f64,
    tag: *const i64,
    nall: i64,
    nlocal: i64,
}

impl RawAtoms {
    /// The arrays as slices, or null status.
    unsafe fn view(&self) -> Result<ListAtoms<'_>, i32> {
        let Some([nall, nlocal]) = counts(&[self.nall, self.nlocal]).map(|c| [c[0], c[1]]) else {
            return Err(BPM_ERR_NULL);
        };
        let arrays = [self.x, self.v, self.omega, self.radius, self.rmass];
        if nlocal > nall || (nall > 0 && (arrays.iter().any(|p| p.is_null()) || self.tag.is_null()))
        {
            return Err(BPM_ERR_NULL);
        }
        Ok(ListAtoms {
            x: rows(self.x, nall),
            v: rows(self.v, nall),
            omega: rows(self.omega, nall),
            radius: list(self.radius, nall),
            mass: list(self.rmass, nall),
            tag: list(self.tag, nall),
            n_owned: nlocal,
        })
    }
}

/// What pass 1 found over a rank's atoms (`bpm_granular_summary`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct RawSummary {
    /// Largest correction over its atom's radius (0 if none is positive).
    pub largest: f64,
    /// Contacts (whole-contact switch) or terms (per-term switch) the
    /// advanced closure switched off.
    pub switched_off: i64,
}

/// The atoms and the list rows of a pass, checked: rows of owned atoms
/// only (newton off: the memory is theirs), indices below `nall`.
///
/// # Safety
/// As [`bpm_granular_corrections`].
unsafe fn pass_inputs<'a>(
    atoms: &'a RawAtoms,
    inum: i64,
    ilist: *const i32,
    numneigh: *const i32,
    firstneigh: *const *const i32,
) -> Result<(ListAtoms<'a>, impl Iterator<Item = (usize, &'a [i32])> + 'a), i32> {
    let atoms = atoms.view()?;
    let nall = atoms.x.len();
    let inum = counts(&[inum]).map(|c| c[0]).ok_or(BPM_ERR_NULL)?;
    if inum > 0 && (ilist.is_null() || numneigh.is_null() || firstneigh.is_null()) {
        return Err(BPM_ERR_NULL);
    }
    let ilist = list(ilist, inum);
    if ilist.iter().any(|&i| i as usize >= atoms.n_owned) {
        return Err(BPM_ERR_INDEX);
    }
    let rows = half_list(ilist, numneigh, firstneigh, nall)?;
    Ok((atoms, rows))
}

/// Pass 1: the corrections of every owned atom's contacts into
/// `corrections` (`nall` rows of `1 + 2 slots` doubles; owned rows
/// written), from the contact memory `history` (`nlocal` rows of `1 + 9
/// slots`), and what it found to `summary` (if not null). Without the
/// closure, empties the owned rows. On a stop
/// (BPM_ERR_STOPPED) writes why to `message`.
///
/// # Safety
/// Arrays as [`RawAtoms`] says; the list as [`super::bpm_pair_forces`];
/// `history` and `corrections` sized as above; `message` `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_corrections(
    style: *mut GranularStyle,
    atoms: *const RawAtoms,
    inum: i64,
    ilist: *const i32,
    numneigh: *const i32,
    firstneigh: *const *const i32,
    history: *const f64,
    corrections: *mut f64,
    step: i64,
    summary: *mut RawSummary,
    message: *mut c_char,
    len: i64,
) -> i32 {
    guard(|| {
        let (Some(style), Some(atoms)) = (style.as_mut(), atoms.as_ref()) else {
            return BPM_ERR_NULL;
        };
        let (atoms, rows_in) = match pass_inputs(atoms, inum, ilist, numneigh, firstneigh) {
            Ok(inputs) => inputs,
            Err(status) => return status,
        };
        let nall = atoms.x.len();
        let slots = style.coeffs.slots;
        if nall > 0 && (history.is_null() || corrections.is_null()) {
            return BPM_ERR_NULL;
        }
        let history = list(history, atoms.n_owned * Layout::history(slots).stride());
        let corrections = if nall == 0 {
            &mut []
        } else {
            slice::from_raw_parts_mut(corrections, nall * Layout::corrections(slots).stride())
        };
        match style
            .list
            .corrections(&atoms, rows_in, history, corrections, step)
        {
            Ok(found) => {
                if let Some(out) = summary.as_mut() {
                    *out = RawSummary {
                        largest: found.largest,
                        switched_off: found.switched_off as i64,
                    };
                }
                BPM_OK
            }
            Err(e) => {
                write_message(&e.to_string(), message, len);
                BPM_ERR_STOPPED
            }
        }
    })
}

/// Pass 2: the contact forces and torques of the listed pairs on owned
/// atoms (newton off), added to `f` and `torque` (`3 nall` doubles each),
/// with the corrections complete on ghosts; the contact memory advanced
/// over `dt` when `update` is not 0 (a step, not a set-up); with `renew`
/// not 0 (the list was rebuilt) the memory keeps only the listed contacts.
/// The virial
/// goes to `tally` (null: not summed). On a stop (BPM_ERR_STOPPED) writes
/// why to `message`.
///
/// # Safety
/// As [`bpm_granular_corrections`]; `history` writable.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_forces(
    style: *mut GranularStyle,
    atoms: *const RawAtoms,
    inum: i64,
    ilist: *const i32,
    numneigh: *const i32,
    firstneigh: *const *const i32,
    corrections: *const f64,
    history: *mut f64,
    f: *mut f64,
    torque: *mut f64,
    dt: f64,
    update: i32,
    renew: i32,
    step: i64,
    tally: *mut Tally,
    message: *mut c_char,
    len: i64,
) -> i32 {
    guard(|| {
        let (Some(style), Some(atoms)) = (style.as_mut(), atoms.as_ref()) else {
            return BPM_ERR_NULL;
        };
        let (atoms, rows_in) = match pass_inputs(atoms, inum, ilist, numneigh, firstneigh) {
            Ok(inputs) => inputs,
            Err(status) => return status,
        };
        let nall = atoms.x.len();
        let slots = style.coeffs.slots;
        if nall > 0
            && (history.is_null() || corrections.is_null() || f.is_null() || torque.is_null())
        {
            return BPM_ERR_NULL;
        }
        let (history, f, torque) = if nall == 0 {
            (&mut [][..], &mut [][..], &mut [][..])
        } else {
            (
                slice::from_raw_parts_mut(history, atoms.n_owned * Layout::history(slots).stride()),
                slice::from_raw_parts_mut(f as *mut [f64; 3], nall),
                slice::from_raw_parts_mut(torque as *mut [f64; 3], nall),
            )
        };
        let corrections = list(corrections, nall * Layout::corrections(slots).stride());
        match style.list.forces(
            &atoms,
            rows_in,
            corrections,
            history,
            f,
            torque,
            dt,
            update != 0,
            renew != 0,
            step,
        ) {
            Ok(t) => {
                if let Some(out) = tally.as_mut() {
                    *out = t;
                }
                BPM_OK
            }
            Err(e) => {
                write_message(&e.to_string(), message, len);
                BPM_ERR_STOPPED
            }
        }
    })
}

/// The material of a `fix bpm/granular/wall`: parses the `nwords` words
/// ([`parse_wall_material`]) into a new handle; on bad input returns null
/// and writes why to `message`.
///
/// # Safety
/// `words` holds `nwords` NUL-terminated strings; `message` `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_wall_material_create(
    nwords: i32,
    words: *const *const c_char,
    message: *mut c_char,
    len: i64,
) -> *mut GranularMaterial {
    parsed_handle(nwords, words, message, len, parse_wall_material)
}

/// Frees a wall material (null: nothing).
///
/// # Safety
/// `material` is null or from [`bpm_granular_wall_material_create`], not
/// freed before.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_wall_material_destroy(material: *mut GranularMaterial) {
    if !material.is_null() {
        drop(Box::from_raw(material));
    }
}

/// A flat wall at one force evaluation (`bpm_granular_wall`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RawWall {
    /// The wall's number, >= 1: its contacts are kept under `-number`.
    pub number: i64,
    /// Axis normal to the plane: 0, 1 or 2.
    pub axis: i32,
    /// +1 when the atoms are above the plane, -1 below.
    pub side: i32,
    /// The plane's position now.
    pub position: f64,
    /// Its speed along the axis.
    pub velocity: f64,
    /// Not 0 when the wall was (re)defined since the last evaluation.
    pub fresh: i32,
    /// Not 0 when a fresh wall keeps the friction springs of the wall it
    /// replaces (same number, axis and side).
    pub keep: i32,
    /// Its material, from [`bpm_granular_wall_material_create`].
    pub material: *const GranularMaterial,
}

// `bpm_granular_wall` in bpm_kernels.h has this layout (checked there too).
const _: () = assert!(
    std::mem::size_of::<RawWall>() == 48
        && std::mem::offset_of!(RawWall, fresh) == 32
        && std::mem::offset_of!(RawWall, keep) == 36
        && std::mem::offset_of!(RawWall, material) == 40
);

/// Sets the `nwalls` walls of the coming passes ([`GranularList::set_walls`]):
/// their coefficients mix each wall's material with the spheres'; fresh
/// walls restart the friction springs of the contacts in `history`
/// (`nlocal` memory rows), unless `keep` and the wall replaces one of its
/// number, axis and side. On bad walls (a number below 1 or shared, an
/// axis not 0 to 2, a side not +1 or -1) returns BPM_ERR_STOPPED with why
/// in `message`.
///
/// # Safety
/// `walls` holds `nwalls` walls with live materials; `history` `nlocal`
/// rows; `message` `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_set_walls(
    style: *mut GranularStyle,
    walls: *const RawWall,
    nwalls: i64,
    history: *mut f64,
    nlocal: i64,
    message: *mut c_char,
    len: i64,
) -> i32 {
    guard(|| {
        let Some(style) = style.as_mut() else {
            return BPM_ERR_NULL;
        };
        let Some([nwalls, nlocal]) = counts(&[nwalls, nlocal]).map(|c| [c[0], c[1]]) else {
            return BPM_ERR_NULL;
        };
        if (nwalls > 0 && walls.is_null()) || (nlocal > 0 && history.is_null()) {
            return BPM_ERR_NULL;
        }
        // Buffers of the handle: no allocation per step.
        let (set, fresh) = (&mut style.walls, &mut style.fresh);
        set.clear();
        fresh.clear();
        for w in list(walls, nwalls) {
            let Some(material) = w.material.as_ref() else {
                return BPM_ERR_NULL;
            };
            set.push(ListWall {
                number: w.number,
                plane: WallPlane {
                    axis: usize::try_from(w.axis).unwrap_or(usize::MAX),
                    sign: w.side as f64,
                    position: w.position,
                    velocity: w.velocity,
                },
                coeffs: GranularCoeffs::between(&style.coeffs.material, material),
                keep_history: w.keep != 0,
            });
            fresh.push(w.fresh != 0);
        }
        let stride = Layout::history(style.coeffs.slots).stride();
        let history = if nlocal == 0 {
            &mut []
        } else {
            slice::from_raw_parts_mut(history, nlocal * stride)
        };
        match style
            .list
            .set_walls(&style.walls, &style.fresh, history, nlocal)
        {
            Ok(()) => BPM_OK,
            Err(e) => {
                write_message(&e.to_string(), message, len);
                BPM_ERR_STOPPED
            }
        }
    })
}

/// Hands the walls `from` set last over to `to` (a handle made anew by a
/// later `pair_coeff`), so that walls defined anew keep their loads
/// ([`GranularList::inherit_walls`]). Nulls: nothing.
///
/// # Safety
/// Each is null or a live handle, not the same one.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_inherit_walls(
    to: *mut GranularStyle,
    from: *const GranularStyle,
) -> i32 {
    guard(|| {
        if let (Some(to), Some(from)) = (to.as_mut(), from.as_ref()) {
            to.list.inherit_walls(&from.list);
        }
        BPM_OK
    })
}

/// Copies to `out` (`nwalls` doubles, as many as were set) the normal
/// force on each wall from this rank's atoms in the last forces pass
/// (positive when pushed).
///
/// # Safety
/// `out` holds `nwalls` doubles.
#[no_mangle]
pub unsafe extern "C" fn bpm_granular_wall_forces(
    style: *const GranularStyle,
    out: *mut f64,
    nwalls: i64,
) -> i32 {
    guard(|| {
        let Some(style) = style.as_ref() else {
            return BPM_ERR_NULL;
        };
        let forces = style.list.wall_forces();
        if nwalls != forces.len() as i64 {
            return BPM_ERR_INDEX;
        }
        if !forces.is_empty() {
            if out.is_null() {
                return BPM_ERR_NULL;
            }
            slice::from_raw_parts_mut(out, forces.len()).copy_from_slice(forces);
        }
        BPM_OK
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_distances_of_a_tilted_box() {
        // Orthogonal: the edges.
        assert_eq!(
            face_distances(&[2.0, 3.0, 4.0, 0.0, 0.0, 0.0]),
            [2.0, 3.0, 4.0]
        );
        // Tilted by xy = yprd: the x faces come closer by sqrt(2).
        let d = face_distances(&[2.0, 2.0, 4.0, 0.0, 0.0, 2.0]);
        assert!((d[0] - 2.0 / 2f64.sqrt()).abs() < 1e-15 && d[1] == 2.0 && d[2] == 4.0);
        // Tilted by yz = zprd: the y faces come closer by sqrt(2), the x
        // faces stay; by xz = zprd: the x faces come closer.
        let d = face_distances(&[2.0, 3.0, 3.0, 3.0, 0.0, 0.0]);
        assert!(d[0] == 2.0 && (d[1] - 3.0 / 2f64.sqrt()).abs() < 1e-15 && d[2] == 3.0);
        let d = face_distances(&[3.0, 2.0, 3.0, 0.0, 3.0, 0.0]);
        assert!((d[0] - 3.0 / 2f64.sqrt()).abs() < 1e-15 && d[1] == 2.0 && d[2] == 3.0);
    }

    #[test]
    fn coefficients_parse_with_every_option_and_bad_ones_are_named() {
        let words = "hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 \
                     rolling sds 300 5 0.2 twisting marshall \
                     multicontact 0.81 mpr 0.11 switch per_term test magnitude reach 0.3 slots 40";
        let c = parse_coeffs(&words.split_whitespace().collect::<Vec<_>>()).unwrap();
        assert_eq!(c.material.youngs_modulus, 1000.0);
        assert_eq!(c.material.restitution, 0.5);
        assert_eq!(c.material.poisson_ratio, 0.3);
        assert_eq!(c.material.rolling.unwrap().friction, 0.2);
        assert_eq!(c.material.twisting, Twisting::Marshall);
        let m = c.multicontact.unwrap();
        assert_eq!(
            (m.prefactor, m.max_penetration_ratio, m.reach),
            (0.81, Some(0.11), 0.3)
        );
        assert_eq!((m.switch, m.test), (MprSwitch::PerTerm, MprTest::Magnitude));
        assert_eq!(c.slots, 40);
        let plain = "hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5";
        let c = parse_coeffs(&plain.split_whitespace().collect::<Vec<_>>()).unwrap();
        assert_eq!((c.multicontact, c.slots), (None, DEFAULT_SLOTS));
        for (bad, says) in [
            ("hertz/material -1 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5", "youngs_modulus"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1", "mu_s"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 x", "mu_s"),
            ("hertz 1000 0.5 0.3", "hertz/material"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 multicontact -1", "prefactor"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 multicontact 0.8 reach 0", "reach"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 slots 0", "slots"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 bogus", "bogus"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 slots 8 slots 9", "twice"),
            ("hertz/material 1000 0.5 0.3 damping tsuji tangential mindlin NULL 1 0.5 multicontact 0.8 reach 0.2 reach 0.3", "twice"),
        ] {
            let err = parse_coeffs(&bad.split_whitespace().collect::<Vec<_>>()).unwrap_err();
            assert!(err.contains(says), "{bad}: {err}");
        }
    }
}
