//! The scenario's random streams: SplitMix64, small and seeded.
//!
//! Every random process of a run (generated robot positions, random and
//! intentional obstacle motion, sensor noise) draws from its own stream,
//! derived from the scenario's `world.seed`, a tag naming the process and an
//! index (the obstacle's or robot's), so that adding noise to one robot does
//! not change another's obstacles, and the same seed gives the same run.

/// SplitMix64 (Steele, Lea & Flood 2014): one `u64` of state, passes
/// BigCrush, plenty for simulation noise.
#[derive(Debug, Clone)]
pub struct Rng(pub(crate) u64);

impl Rng {
    /// A stream seeded with `seed` directly.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The stream of process `tag` for body `index`, under scenario seed
    /// `seed`. Different tags or indices give unrelated streams.
    pub fn stream(seed: u64, tag: &str, index: u64) -> Self {
        // FNV-1a of the tag, then two SplitMix rounds to mix in seed and index.
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in tag.bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
        let mut r = Rng(seed ^ h);
        let a = r.next_u64();
        let mut r = Rng(a ^ index.wrapping_mul(0xD6E8_FEB8_6659_FD93));
        Rng(r.next_u64())
    }

    /// The lidar noise of robot `robot` at tick `tick`: a fresh stream per
    /// robot and tick, so the agent's scan and the world's recorded one
    /// draw the same numbers whatever ticks either skipped.
    pub fn lidar(seed: u64, robot: u64, tick: u64) -> Self {
        Self::stream(seed, "lidar-noise", (robot << 40) ^ tick)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Standard normal, by Box-Muller (one of the pair; simple and exact).
    pub fn gaussian(&mut self) -> f64 {
        // 1 - unit() is in (0, 1], so the log is finite.
        let u1 = 1.0 - self.unit();
        let u2 = self.unit();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_differ_by_tag_and_index_and_repeat_by_seed() {
        let first = |s: u64, t: &str, i: u64| Rng::stream(s, t, i).next_u64();
        assert_eq!(first(1, "a", 0), first(1, "a", 0));
        assert_ne!(first(1, "a", 0), first(1, "a", 1));
        assert_ne!(first(1, "a", 0), first(1, "b", 0));
        assert_ne!(first(1, "a", 0), first(2, "a", 0));
    }

    #[test]
    fn gaussian_has_zero_mean_and_unit_variance() {
        let mut r = Rng::new(7);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| r.gaussian()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        // Standard errors: 1/sqrt(n) for the mean, sqrt(2/n) for the variance; 4 of each.
        let n = n as f64;
        assert!(mean.abs() < 4.0 / n.sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 4.0 * (2.0 / n).sqrt(), "variance {var}");
    }
}
