//! Per-stage wall-clock timers, so every benchmark says where time goes.

use std::time::{Duration, Instant};

/// The parts of a step that are timed separately.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// Volume proxies `V_i`.
    Volumes,
    /// Bond forces.
    Bonds,
    /// Pair forces.
    Pairs,
    /// Neighbour-list checks and rebuilds.
    Neighbours,
    /// Walls, tethers, viscous damping.
    External,
    /// Velocity Verlet updates, box deformation, barostat.
    Integrate,
}

impl Stage {
    /// Every stage, in report order.
    pub const ALL: [Stage; 6] = [
        Stage::Volumes,
        Stage::Bonds,
        Stage::Pairs,
        Stage::Neighbours,
        Stage::External,
        Stage::Integrate,
    ];

    /// A short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Volumes => "volumes",
            Stage::Bonds => "bonds",
            Stage::Pairs => "pairs",
            Stage::Neighbours => "neighbours",
            Stage::External => "external",
            Stage::Integrate => "integrate",
        }
    }
}

/// Accumulated time per stage.
#[derive(Clone, Debug, Default)]
pub struct Timers {
    totals: [Duration; 6],
}

/// Adds the time since its creation to one stage when dropped.
pub struct Running<'a> {
    timers: &'a mut Timers,
    stage: Stage,
    start: Instant,
}

impl Drop for Running<'_> {
    fn drop(&mut self) {
        self.timers.totals[self.stage as usize] += self.start.elapsed();
    }
}

impl Timers {
    /// Starts timing `stage` until the returned guard drops.
    pub fn start(&mut self, stage: Stage) -> Running<'_> {
        Running {
            timers: self,
            stage,
            start: Instant::now(),
        }
    }

    /// Time spent in `stage`.
    pub fn total(&self, stage: Stage) -> Duration {
        self.totals[stage as usize]
    }
}
