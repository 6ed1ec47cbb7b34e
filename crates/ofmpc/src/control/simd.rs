//! Run-time CPU feature detection as a token: a value of [`Avx2Fma`] exists
//! only on a CPU that runs AVX2 and FMA instructions, so a safe function that
//! takes one can call `#[target_feature(enable = "avx2,fma")]` code soundly.
//! The detection is cached by the standard library.

/// Proof that the running CPU supports AVX2 and FMA. Cannot be built outside
/// [`Avx2Fma::detect`] (private field).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Avx2Fma(());

impl Avx2Fma {
    /// `Some` when the CPU supports AVX2 and FMA (always `None` off x86-64).
    #[inline]
    pub(crate) fn detect() -> Option<Self> {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                return Some(Self(()));
            }
        }
        None
    }
}
