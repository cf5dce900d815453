//! Which instruction set a kernel runs on.
//!
//! The kernels are written once, as plain loops over per-lane arrays, and
//! compiled twice: for the baseline of the target (portable; two lanes of
//! SSE2 on x86-64) and, on x86-64, for AVX2 (four lanes), chosen at run
//! time. Neither build contracts multiplies and adds into fused ones (Rust
//! never does), so both give the same result bit for bit.

/// An instruction set the kernels are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Isa {
    /// The target's baseline.
    Portable,
    /// x86-64 with AVX2 and FMA.
    Avx2,
}

impl Isa {
    /// The widest instruction set this processor runs.
    #[inline]
    pub fn detect() -> Self {
        if Isa::Avx2.available() {
            Isa::Avx2
        } else {
            Isa::Portable
        }
    }

    /// Whether this processor runs `self`.
    #[inline]
    pub fn available(self) -> bool {
        match self {
            Isa::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
            }
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Avx2 => false,
        }
    }

    /// Short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Portable => "portable",
            Isa::Avx2 => "avx2",
        }
    }
}
