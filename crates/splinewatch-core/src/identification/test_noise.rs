//! Seeded uniform noise for the identification's unit tests: xorshift64
//! (Marsaglia 2003), values in `[−0.5, 0.5)`, the same sequence on every
//! platform.

/// `n` values in `[−0.5, 0.5)` from `seed`.
pub(crate) fn uniform_noise(seed: u64, n: usize) -> Vec<f64> {
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}
