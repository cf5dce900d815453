//! Checks a scene once, at load, with errors that name the field.

use super::model::{ForceField, Mass, ModelKind, Scene, StageSpec, SCENE_VERSION};
use crate::engine::{MultiContact, SimBox};
use crate::kernels::{
    GranularMaterial, MprSwitch, MprTest, Separation, SpringDashpotSlider, Twisting,
};

/// Why a scene could not be used.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read or written.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: String,
        /// The cause (in the message, not chained, so it prints once).
        cause: std::io::Error,
    },
    /// The JSON did not match the scene format (names the field and line).
    #[error("scene is not valid JSON for the scene format: {0}")]
    Parse(serde_json::Error),
    /// A value is out of range or inconsistent.
    #[error("field `{field}`: {reason}")]
    Invalid {
        /// Dotted path of the offending field.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
}

impl From<serde_json::Error> for SceneError {
    fn from(e: serde_json::Error) -> Self {
        SceneError::Parse(e)
    }
}

fn invalid(field: impl Into<String>, reason: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        field: field.into(),
        reason: reason.into(),
    }
}

fn finite(field: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(field, format!("must be a finite number (got {v})")))
    }
}

fn non_negative(field: &str, v: f64) -> Result<f64, SceneError> {
    if finite(field, v)? < 0.0 {
        return Err(invalid(field, format!("must be >= 0 (got {v})")));
    }
    Ok(v)
}

fn positive(field: &str, v: f64) -> Result<f64, SceneError> {
    if finite(field, v)? <= 0.0 {
        return Err(invalid(field, format!("must be > 0 (got {v})")));
    }
    Ok(v)
}

fn finite_rows(field: &str, rows: &[[f64; 3]]) -> Result<(), SceneError> {
    if let Some(i) = rows.iter().position(|r| !r.iter().all(|c| c.is_finite())) {
        return Err(invalid(format!("{field}[{i}]"), "must be finite"));
    }
    Ok(())
}

/// The engine's box for a scene's box spec.
pub fn simbox_of(scene: &Scene) -> SimBox {
    SimBox {
        lo: scene.simbox.lo,
        lengths: scene.simbox.lengths,
        tilt: scene.simbox.tilt,
        periodic: scene.simbox.periodic,
    }
}

pub(crate) fn check_granular(prefix: &str, m: &GranularMaterial) -> Result<(), SceneError> {
    positive(&format!("{prefix}.youngs_modulus"), m.youngs_modulus)?;
    let nu = finite(&format!("{prefix}.poisson_ratio"), m.poisson_ratio)?;
    if !(nu > -1.0 && nu <= 0.5) {
        return Err(invalid(
            format!("{prefix}.poisson_ratio"),
            format!("must lie in (-1, 1/2] (got {nu})"),
        ));
    }
    let e = finite(&format!("{prefix}.restitution"), m.restitution)?;
    if !(e > 0.0 && e <= 1.0) {
        return Err(invalid(
            format!("{prefix}.restitution"),
            format!("must lie in (0, 1] (got {e})"),
        ));
    }
    non_negative(
        &format!("{prefix}.tangential_damping"),
        m.tangential_damping,
    )?;
    non_negative(&format!("{prefix}.sliding_friction"), m.sliding_friction)?;
    let slider = |name: &str, sds: &SpringDashpotSlider| -> Result<(), SceneError> {
        positive(&format!("{prefix}.{name}.stiffness"), sds.stiffness)?;
        non_negative(&format!("{prefix}.{name}.damping"), sds.damping)?;
        non_negative(&format!("{prefix}.{name}.friction"), sds.friction)?;
        Ok(())
    };
    if let Some(r) = &m.rolling {
        slider("rolling", r)?;
    }
    if let Twisting::Sds(t) = &m.twisting {
        slider("twisting.sds", t)?;
    }
    Ok(())
}

pub(crate) fn check_multicontact(prefix: &str, m: &MultiContact) -> Result<(), SceneError> {
    non_negative(&format!("{prefix}.prefactor"), m.prefactor)?;
    match m.max_penetration_ratio {
        Some(mpr) => {
            non_negative(&format!("{prefix}.max_penetration_ratio"), mpr)?;
        }
        None if m.switch != MprSwitch::default() || m.test != MprTest::default() => {
            return Err(invalid(
                prefix,
                "`switch` and `test` belong to the advanced closure: give `max_penetration_ratio` too",
            ))
        }
        None => {}
    }
    positive(&format!("{prefix}.reach"), m.reach)?;
    Ok(())
}

/// Checks a force field of a scene of `model`; `bonded` says whether the
/// scene has bonds (then the bonded particle model needs bond
/// coefficients: a missing `bond` defaults to zero, which would switch the
/// bonds off silently).
fn check_force_field(
    prefix: &str,
    ff: &ForceField,
    model: ModelKind,
    bonded: bool,
) -> Result<(), SceneError> {
    if model == ModelKind::Bpm && bonded && ff.bond.is_zero() {
        return Err(invalid(
            format!("{prefix}.bond"),
            "is missing or all zero, but the scene has bonds: give k, a and gamma (a stage's force_field replaces the whole force field)",
        ));
    }
    match (model, &ff.granular) {
        (ModelKind::Dem, None) => {
            return Err(invalid(
                format!("{prefix}.granular"),
                "model dem needs the sphere material (youngs_modulus, poisson_ratio, restitution, tangential_damping, sliding_friction)",
            ))
        }
        (ModelKind::Dem, Some(m)) => {
            check_granular(&format!("{prefix}.granular"), m)?;
            if !ff.bond.is_zero() || ff.pair.is_some() || ff.zero_net_multibody || ff.overlay_pair
            {
                return Err(invalid(
                    prefix,
                    "model dem has no bonds and no bpm contacts: leave out bond, pair, \
                     overlay_pair and zero_net_multibody",
                ));
            }
        }
        (ModelKind::Bpm, Some(_)) => {
            return Err(invalid(
                format!("{prefix}.granular"),
                "belongs to model dem; this scene is model bpm (set \"model\": \"dem\" for spheres)",
            ))
        }
        (ModelKind::Bpm, None) => {}
    }
    match (model, &ff.multicontact) {
        (ModelKind::Dem, Some(m)) => check_multicontact(&format!("{prefix}.multicontact"), m)?,
        (ModelKind::Bpm, Some(_)) => {
            return Err(invalid(
                format!("{prefix}.multicontact"),
                "is a closure of DEM sphere contacts (model dem); the bonded model's grains deform by themselves",
            ))
        }
        (_, None) => {}
    }
    if let Some(failure) = &ff.bond_failure {
        let field = format!("{prefix}.bond_failure");
        if model == ModelKind::Dem {
            return Err(invalid(field, "belongs to the bonded model (model bpm)"));
        }
        failure
            .check()
            .map_err(|e| invalid(field.clone(), e.to_string()))?;
        if ff.zero_net_multibody && failure.is_live() {
            return Err(invalid(
                field,
                "the zero-net-multibody variant does not combine with bonds that break or yield yet: \
                 leave out zero_net_multibody or bond_failure",
            ));
        }
    }
    if ff.overlay_pair && ff.pair.is_none() {
        return Err(invalid(
            format!("{prefix}.overlay_pair"),
            "overlays the contact law on bonds, but there is no contact law: give pair, or leave \
             out overlay_pair",
        ));
    }
    non_negative(&format!("{prefix}.bond.k"), ff.bond.k)?;
    finite(&format!("{prefix}.bond.a"), ff.bond.a)?;
    non_negative(&format!("{prefix}.bond.gamma"), ff.bond.gamma)?;
    if let Some(p) = &ff.pair {
        non_negative(&format!("{prefix}.pair.k"), p.k)?;
        positive(&format!("{prefix}.pair.d"), p.d)?;
        non_negative(&format!("{prefix}.pair.a"), p.a)?;
        non_negative(&format!("{prefix}.pair.gamma"), p.gamma)?;
    }
    non_negative(&format!("{prefix}.skin"), ff.skin)?;
    if let Some(g) = &ff.gravity {
        for (d, c) in g.iter().enumerate() {
            finite(&format!("{prefix}.gravity[{d}]"), *c)?;
        }
    }
    Ok(())
}

/// The largest pair interaction range plus skin over the scene's force fields.
fn max_list_cutoff(scene: &Scene) -> (f64, &'static str) {
    if scene.model == ModelKind::Dem {
        let radius = scene
            .particles
            .radius
            .as_deref()
            .unwrap_or(&[crate::engine::particles::DEFAULT_RADIUS]);
        let diameter = 2.0 * radius.iter().copied().fold(0.0, f64::max);
        let fields = || {
            std::iter::once(&scene.force_field)
                .chain(scene.stages.iter().filter_map(|s| s.force_field.as_ref()))
        };
        let skin = fields().map(|ff| ff.skin).fold(0.0, f64::max);
        // The multi-contact closure reaches beyond touching.
        let reach = fields()
            .filter_map(|ff| ff.multicontact.map(|m| m.reach))
            .fold(0.0, f64::max);
        if reach > 0.0 {
            return (
                diameter * (1.0 + reach) + skin,
                "the largest sphere diameter x (1 + multicontact.reach) + skin",
            );
        }
        return (diameter + skin, "the largest sphere diameter + skin");
    }
    let of = |ff: &ForceField| ff.pair.map_or(0.0, |p| p.d + ff.skin);
    let mut cut = of(&scene.force_field);
    for s in &scene.stages {
        if let Some(ff) = &s.force_field {
            cut = cut.max(of(ff));
        }
    }
    (cut, "force_field.pair.d + skin")
}

/// The placement of a flat wall (harmonic or granular) named `q`.
fn check_flat_wall(
    q: &str,
    axis: usize,
    position: f64,
    velocity: f64,
    periodic: [bool; 3],
) -> Result<(), SceneError> {
    if axis > 2 {
        return Err(invalid(
            format!("{q}.axis"),
            format!("must be 0, 1 or 2 (got {axis})"),
        ));
    }
    if periodic[axis] {
        return Err(invalid(
            format!("{q}.axis"),
            "a wall needs a non-periodic dimension",
        ));
    }
    finite(&format!("{q}.position"), position)?;
    finite(&format!("{q}.velocity"), velocity)?;
    Ok(())
}

fn check_stage(i: usize, stage: &StageSpec, scene: &Scene) -> Result<(), SceneError> {
    let (simbox, n, model) = (
        &simbox_of(scene),
        scene.particles.positions.len(),
        scene.model,
    );
    let p = format!("stages[{i}]");
    positive(&format!("{p}.dt"), stage.dt)?;
    non_negative(&format!("{p}.viscous"), stage.viscous)?;
    if let Some(ff) = &stage.force_field {
        let field = format!("{p}.force_field");
        check_force_field(&field, ff, model, !scene.bonds.pairs.is_empty())?;
        // LAMMPS sizes each contact's history once, for the rolling and
        // twisting models of the first pair_coeff: they cannot change.
        if let (Some(new), Some(old)) = (&ff.granular, &scene.force_field.granular) {
            if new.rolling.is_some() != old.rolling.is_some()
                || (new.twisting == Twisting::None) != (old.twisting == Twisting::None)
            {
                return Err(invalid(
                    format!("{field}.granular"),
                    "switches rolling or twisting resistance on or off: a run keeps the models it starts with (their coefficients may change)",
                ));
            }
        }
    }
    if model == ModelKind::Dem && stage.tether.as_ref().is_some_and(|t| t.grain.is_some()) {
        return Err(invalid(
            format!("{p}.tether.grain"),
            "DEM spheres have no grains to pick: tether them all (leave out grain)",
        ));
    }
    if model == ModelKind::Dem && stage.reset_reference {
        return Err(invalid(
            format!("{p}.reset_reference"),
            "model dem has no bonds to reset",
        ));
    }
    if let Some(vi) = &stage.set_velocities {
        non_negative(&format!("{p}.set_velocities.rms_speed"), vi.rms_speed)?;
        if n < 2 && vi.rms_speed > 0.0 {
            return Err(invalid(
                format!("{p}.set_velocities"),
                "needs at least 2 particles",
            ));
        }
    }
    for (w, wall) in stage.walls.iter().enumerate() {
        let q = format!("{p}.walls[{w}]");
        check_flat_wall(&q, wall.axis, wall.position, wall.velocity, simbox.periodic)?;
        non_negative(&format!("{q}.stiffness"), wall.stiffness)?;
        positive(&format!("{q}.cutoff"), wall.cutoff)?;
    }
    for (w, wall) in stage.granular_walls.iter().enumerate() {
        let q = format!("{p}.granular_walls[{w}]");
        if model != ModelKind::Dem {
            return Err(invalid(
                q,
                "granular walls touch DEM spheres (model dem); the bonded model's walls are the harmonic `walls`",
            ));
        }
        check_flat_wall(&q, wall.axis, wall.position, wall.velocity, simbox.periodic)?;
        check_granular(&format!("{q}.material"), &wall.material)?;
        // The first stage's walls meet the scene's own positions: a sphere
        // on the wrong side would stop the native run at once, and LAMMPS
        // would let it through without a word.
        if i == 0 {
            let sign = match wall.side {
                crate::engine::WallSide::Lo => 1.0,
                crate::engine::WallSide::Hi => -1.0,
            };
            if let Some(k) = scene
                .particles
                .positions
                .iter()
                .position(|x| sign * (x[wall.axis] - wall.position) <= 0.0)
            {
                return Err(invalid(
                    format!("{q}.position"),
                    format!(
                        "sphere {k} starts on or behind the wall's plane (side {:?}): spheres must start on the side the wall faces",
                        wall.side
                    ),
                ));
            }
        }
    }
    if let Some(s) = &stage.sphere_wall {
        let q = format!("{p}.sphere_wall");
        finite_rows(&format!("{q}.centre"), &[s.centre])?;
        positive(&format!("{q}.radius"), s.radius)?;
        finite(&format!("{q}.velocity"), s.velocity)?;
        let end = s.radius + s.velocity * stage.steps as f64 * stage.dt;
        if s.velocity < 0.0 && end <= s.cutoff {
            return Err(invalid(
                format!("{q}.velocity"),
                format!(
                    "shrinks the sphere to radius {end} by the end of the stage: it must stay above the cutoff {}",
                    s.cutoff
                ),
            ));
        }
        non_negative(&format!("{q}.amplitude"), s.amplitude)?;
        positive(&format!("{q}.period"), s.period)?;
        positive(&format!("{q}.decay_time"), s.decay_time)?;
        non_negative(&format!("{q}.stiffness"), s.stiffness)?;
        positive(&format!("{q}.cutoff"), s.cutoff)?;
    }
    if let Some(t) = &stage.tether {
        non_negative(&format!("{p}.tether.stiffness"), t.stiffness)?;
        if let Some(a) = t.anchor {
            finite_rows(&format!("{p}.tether.anchor"), &[a])?;
        }
    }
    if let Some(d) = &stage.deformation {
        use crate::engine::Deformation;
        match d {
            Deformation::Isotropic { true_strain_rate } => {
                finite(
                    &format!("{p}.deformation.isotropic.true_strain_rate"),
                    *true_strain_rate,
                )?;
            }
            Deformation::SimpleShear { tilt, rate, remap } => {
                finite(&format!("{p}.deformation.simple_shear.rate"), *rate)?;
                if tilt.needs_periodic().iter().any(|&d| !simbox.periodic[d]) {
                    return Err(invalid(
                        format!("{p}.deformation.simple_shear.tilt"),
                        "shear by tilt needs both of its dimensions periodic",
                    ));
                }
                // Bond and pair damping of the bonded model read relative
                // velocities without the images' motion.
                if *remap == crate::engine::ShearRemap::V && model != ModelKind::Dem {
                    return Err(invalid(
                        format!("{p}.deformation.simple_shear.remap"),
                        "Lees-Edwards shear (remap \"v\") needs model dem: the bonded model's damping does not see the images' velocities; use remap \"x\"",
                    ));
                }
            }
        }
    }
    if let Some(b) = &stage.barostat {
        finite(&format!("{p}.barostat.target_pressure"), b.target_pressure)?;
        positive(&format!("{p}.barostat.gain"), b.gain)?;
        if !simbox.periodic.iter().any(|&p| p) {
            return Err(invalid(
                format!("{p}.barostat"),
                "needs at least one periodic dimension",
            ));
        }
        if stage.deformation.is_some() {
            // LAMMPS refuses fix press/berendsen and fix deform on the same
            // lengths, and one would undo the other.
            return Err(invalid(
                format!("{p}.barostat"),
                "a stage has either a barostat or a box deformation, not both",
            ));
        }
    }
    Ok(())
}

/// Checks every field of `scene`; returns the first problem found.
pub fn validate(scene: &Scene) -> Result<(), SceneError> {
    if scene.version == 0 || scene.version > SCENE_VERSION {
        return Err(invalid(
            "version",
            format!(
                "scene format {} is not one this bpm {} reads (1 to {SCENE_VERSION}); a newer bpm wrote it",
                scene.version,
                crate::VERSION
            ),
        ));
    }
    let b = &scene.simbox;
    finite_rows("box.lo", &[b.lo])?;
    for d in 0..3 {
        positive(&format!("box.lengths[{d}]"), b.lengths[d])?;
        finite(&format!("box.tilt[{d}]"), b.tilt[d])?;
    }
    // LAMMPS's restricted triclinic limits; they also keep the minimum image exact.
    for (k, (name, base)) in [("xy", 0usize), ("xz", 0), ("yz", 1)].iter().enumerate() {
        if b.tilt[k].abs() > 0.5 * b.lengths[*base] * (1.0 + 1e-12) {
            return Err(invalid(
                format!("box.tilt[{k}]"),
                format!(
                    "tilt {name} = {} exceeds half the box length {}",
                    b.tilt[k], b.lengths[*base]
                ),
            ));
        }
    }
    let simbox = simbox_of(scene);
    let pa = &scene.particles;
    let n = pa.positions.len();
    if n == 0 {
        return Err(invalid("particles.positions", "is empty"));
    }
    finite_rows("particles.positions", &pa.positions)?;
    let per_particle = |field: &str, len: usize| -> Result<(), SceneError> {
        if len != n {
            return Err(invalid(
                field,
                format!("has {len} entries for {n} particles"),
            ));
        }
        Ok(())
    };
    match &pa.mass {
        Mass::Uniform(m) => {
            positive("particles.mass", *m)?;
        }
        Mass::PerParticle(m) => {
            per_particle("particles.mass", m.len())?;
            for (i, &m) in m.iter().enumerate() {
                positive(&format!("particles.mass[{i}]"), m)?;
            }
        }
    }
    if let Some(r) = &pa.radius {
        per_particle("particles.radius", r.len())?;
        for (i, &r) in r.iter().enumerate() {
            positive(&format!("particles.radius[{i}]"), r)?;
        }
    }
    if let Some(t) = &pa.kind {
        per_particle("particles.type", t.len())?;
        if let Some(i) = t.iter().position(|&t| t == 0) {
            return Err(invalid(
                format!("particles.type[{i}]"),
                "types count from 1 (as LAMMPS atom types)",
            ));
        }
    }
    if let Some(ids) = &pa.ids {
        per_particle("particles.ids", ids.len())?;
        if ids.first() == Some(&0) {
            return Err(invalid(
                "particles.ids[0]",
                "atom ids count from 1 (as LAMMPS atom ids)",
            ));
        }
        if let Some(k) = ids.windows(2).position(|w| w[1] <= w[0]) {
            return Err(invalid(
                format!("particles.ids[{}]", k + 1),
                format!(
                    "atom ids must increase strictly, in particle order (id {} follows {})",
                    ids[k + 1],
                    ids[k]
                ),
            ));
        }
    }
    if let Some(v) = &pa.velocities {
        if v.len() != n {
            return Err(invalid(
                "particles.velocities",
                format!("has {} rows for {n} particles", v.len()),
            ));
        }
        finite_rows("particles.velocities", v)?;
    }
    if let Some(w) = &pa.angular_velocities {
        if scene.model != ModelKind::Dem {
            return Err(invalid(
                "particles.angular_velocities",
                "only DEM spheres rotate (model dem)",
            ));
        }
        per_particle("particles.angular_velocities", w.len())?;
        finite_rows("particles.angular_velocities", w)?;
    }
    if let Some(g) = &pa.grain {
        per_particle("particles.grain", g.len())?;
    }
    check_force_field(
        "force_field",
        &scene.force_field,
        scene.model,
        !scene.bonds.pairs.is_empty(),
    )?;
    if scene.model == ModelKind::Dem && !scene.bonds.pairs.is_empty() {
        return Err(invalid(
            "bonds.pairs",
            "model dem has no bonds (each sphere is a whole grain)",
        ));
    }

    let faces = simbox.face_distances();
    let half_face = (0..3)
        .filter(|&d| simbox.periodic[d])
        .map(|d| 0.5 * faces[d])
        .fold(f64::INFINITY, f64::min);
    let (cut, what) = max_list_cutoff(scene);
    if cut >= half_face {
        return Err(invalid(
            "box.lengths",
            format!("{what} = {cut} must be below half the smallest periodic face distance ({half_face})"),
        ));
    }

    let bonds = &scene.bonds;
    if let Some(r0) = &bonds.r0 {
        if r0.len() != bonds.pairs.len() {
            return Err(invalid(
                "bonds.r0",
                format!("has {} entries for {} bonds", r0.len(), bonds.pairs.len()),
            ));
        }
        for (k, &r) in r0.iter().enumerate() {
            positive(&format!("bonds.r0[{k}]"), r)?;
        }
    }
    if let Some(strains) = &bonds.plastic_strain {
        if strains.len() != bonds.pairs.len() {
            return Err(invalid(
                "bonds.plastic_strain",
                format!(
                    "has {} entries for {} bonds",
                    strains.len(),
                    bonds.pairs.len()
                ),
            ));
        }
        if let Some((k, e)) = strains
            .iter()
            .enumerate()
            .find(|(_, e)| !(e.is_finite() && **e > -1.0))
        {
            return Err(invalid(
                format!("bonds.plastic_strain[{k}]"),
                format!(
                    "= {e}: a plastic strain must be finite and above -1 (a positive rest length)"
                ),
            ));
        }
    }
    let mut seen = std::collections::HashSet::with_capacity(bonds.pairs.len());
    for (k, &[i, j]) in bonds.pairs.iter().enumerate() {
        let field = format!("bonds.pairs[{k}]");
        if i >= n || j >= n {
            return Err(invalid(
                field,
                format!("bond ({i}, {j}) refers to a missing particle (there are {n})"),
            ));
        }
        if i == j {
            return Err(invalid(
                field,
                format!("bond ({i}, {j}) joins a particle to itself"),
            ));
        }
        if !seen.insert((i.min(j), i.max(j))) {
            return Err(invalid(field, format!("bond ({i}, {j}) is listed twice")));
        }
        let r = simbox.distance(&pa.positions[i], &pa.positions[j]);
        if r == 0.0 {
            return Err(invalid(
                field,
                format!("bond ({i}, {j}) joins two particles at the same position"),
            ));
        }
        if r >= half_face {
            return Err(invalid(
                field,
                format!("bond ({i}, {j}) is {r} long, not below half the box ({half_face})"),
            ));
        }
    }
    if scene.stages.is_empty() {
        return Err(invalid("stages", "is empty: nothing to run"));
    }
    for (i, stage) in scene.stages.iter().enumerate() {
        check_stage(i, stage, scene)?;
    }
    Ok(())
}
