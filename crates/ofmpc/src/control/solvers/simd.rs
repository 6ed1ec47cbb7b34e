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

/// A zeroed `f64` buffer whose first entry sits on a 64-byte boundary (a
/// cache line, one AVX-512 vector), so that the vector kernels' row blocks,
/// padded to multiples of 8 entries, never straddle cache lines. Safe code:
/// the `Vec` is over-allocated by 7 entries and viewed from the first
/// aligned one. Dereferences to the `len` entries.
#[derive(Debug)]
pub(crate) struct AlignedBuf {
    buf: Vec<f64>,
    off: usize,
    len: usize,
}

impl AlignedBuf {
    /// `len` zeros, 64-byte aligned.
    pub(crate) fn zeros(len: usize) -> Self {
        let buf = vec![0.0f64; len + 7];
        let addr = buf.as_ptr() as usize;
        let off = (64 - addr % 64) % 64 / std::mem::size_of::<f64>();
        Self { buf, off, len }
    }
}

impl Clone for AlignedBuf {
    /// A new aligned allocation with the same entries (the offset of the
    /// original's allocation does not carry over).
    fn clone(&self) -> Self {
        let mut out = Self::zeros(self.len);
        out.copy_from_slice(self);
        out
    }
}

impl std::ops::Deref for AlignedBuf {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.buf[self.off..self.off + self.len]
    }
}

impl std::ops::DerefMut for AlignedBuf {
    fn deref_mut(&mut self) -> &mut [f64] {
        &mut self.buf[self.off..self.off + self.len]
    }
}

#[cfg(test)]
mod tests {
    use crate::control::solvers::simd::AlignedBuf;

    #[test]
    fn aligned_buffers_start_on_a_cache_line_and_clone_aligned() {
        for len in [0, 1, 7, 8, 100, 1000] {
            let mut a = AlignedBuf::zeros(len);
            assert_eq!(a.len(), len);
            assert_eq!(a.as_ptr() as usize % 64, 0, "len {len}");
            a.iter_mut().enumerate().for_each(|(i, v)| *v = i as f64);
            let b = a.clone();
            assert_eq!(b.as_ptr() as usize % 64, 0);
            assert_eq!(&*a, &*b);
        }
    }
}
