//! CrowdNav's test set (Chen et al., "Crowd-Robot Interaction:
//! Crowd-aware Robot Navigation with Attention-based Deep Reinforcement
//! Learning", ICRA 2019; the `crowd_sim` package of its code): the people
//! of each test case placed as `CrowdSim.generate_circle_crossing_human`
//! places them, from the same random numbers.
//!
//! CrowdNav seeds NumPy's legacy generator with `np.random.seed(1000 + k)`
//! for test case k (`counter_offset['test']` is `case_capacity['val']`,
//! 1000) and draws every number with `np.random.random()`: MT19937
//! (Matsumoto & Nishimura 1998) seeded by `init_genrand`, each double from
//! two 32-bit outputs as `genrand_res53` makes it. [`Mt19937`] is that
//! generator, so [`CircleCrossing::people`] gives case k's people exactly.
//!
//! Each person, in turn (`generate_circle_crossing_human`):
//! 1. an angle `a = u * pi * 2`, a noise `(u - 0.5) * v_pref` on each axis,
//!    the start `(R cos a + nx, R sin a + ny)` (R the circle's radius);
//! 2. drawn again while the start is nearer than `r_person + r_other +
//!    discomfort_dist` to the position or the goal of the robot or of a
//!    person placed before;
//! 3. the goal is the start mirrored through the centre, `(-x, -y)`.

use serde::{Deserialize, Serialize};

/// NumPy's legacy `RandomState` (MT19937), as `np.random.seed(s)` and
/// `np.random.random()` use it.
#[derive(Clone)]
pub struct Mt19937 {
    state: [u32; 624],
    index: usize,
}

impl std::fmt::Debug for Mt19937 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Mt19937")
            .field("index", &self.index)
            .finish_non_exhaustive()
    }
}

impl Mt19937 {
    /// Seeded as `np.random.seed(seed)` (`init_genrand`).
    pub fn new(seed: u32) -> Self {
        let mut state = [0u32; 624];
        state[0] = seed;
        for i in 1..624 {
            let prev = state[i - 1];
            state[i] = 1_812_433_253u32
                .wrapping_mul(prev ^ (prev >> 30))
                .wrapping_add(i as u32);
        }
        Self { state, index: 624 }
    }

    /// The next 32-bit output (`genrand_int32`).
    pub fn next_u32(&mut self) -> u32 {
        if self.index >= 624 {
            self.twist();
        }
        let mut y = self.state[self.index];
        self.index += 1;
        y ^= y >> 11;
        y ^= (y << 7) & 0x9d2c_5680;
        y ^= (y << 15) & 0xefc6_0000;
        y ^ (y >> 18)
    }

    /// A double in [0, 1) from two outputs, as `np.random.random()`
    /// (`genrand_res53`).
    pub fn random(&mut self) -> f64 {
        let a = f64::from(self.next_u32() >> 5);
        let b = f64::from(self.next_u32() >> 6);
        (a * 67_108_864.0 + b) / 9_007_199_254_740_992.0
    }

    fn twist(&mut self) {
        const UPPER: u32 = 0x8000_0000;
        const LOWER: u32 = 0x7fff_ffff;
        for i in 0..624 {
            let y = (self.state[i] & UPPER) | (self.state[(i + 1) % 624] & LOWER);
            let mut next = self.state[(i + 397) % 624] ^ (y >> 1);
            if y & 1 != 0 {
                next ^= 0x9908_b0df;
            }
            self.state[i] = next;
        }
        self.index = 0;
    }
}

/// CrowdNav's test case k is drawn from seed `TEST_SEED_OFFSET + k`.
pub const TEST_SEED_OFFSET: u32 = 1000;

/// CrowdNav's circle crossing (`env.config`'s `[sim]`, `[humans]`,
/// `[robot]` and `[reward]` `discomfort_dist`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CircleCrossing {
    /// People (`human_num`, 5).
    pub count: usize,
    /// The circle's radius (`circle_radius`, 4 m).
    pub circle_radius: f64,
    /// Each person's radius (0.3 m).
    pub radius: f64,
    /// Each person's preferred speed, also the noise's width (1 m/s).
    pub preferred_speed: f64,
    /// The margin kept at placement (`discomfort_dist`, 0.2 m).
    pub discomfort_dist: f64,
    /// The robot's start ((0, -4)).
    pub robot_start: [f64; 2],
    /// The robot's goal ((0, 4)).
    pub robot_goal: [f64; 2],
    /// The robot's radius (0.3 m).
    pub robot_radius: f64,
}

impl Default for CircleCrossing {
    fn default() -> Self {
        Self {
            count: 5,
            circle_radius: 4.0,
            radius: 0.3,
            preferred_speed: 1.0,
            discomfort_dist: 0.2,
            robot_start: [0.0, -4.0],
            robot_goal: [0.0, 4.0],
            robot_radius: 0.3,
        }
    }
}

/// One person placed: where it starts and where it walks to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Placed {
    /// Start.
    pub start: [f64; 2],
    /// Goal: the start mirrored through the circle's centre.
    pub goal: [f64; 2],
}

impl CircleCrossing {
    /// The people of the case drawn from `seed` (CrowdNav's test case k:
    /// `seed = TEST_SEED_OFFSET + k`).
    pub fn people(&self, seed: u32) -> Vec<Placed> {
        let mut rng = Mt19937::new(seed);
        // Every body placed so far: (position, goal, radius), the robot first.
        let mut placed = vec![(self.robot_start, self.robot_goal, self.robot_radius)];
        let mut people = Vec::with_capacity(self.count);
        for _ in 0..self.count {
            let start = loop {
                let angle = rng.random() * std::f64::consts::PI * 2.0;
                let nx = (rng.random() - 0.5) * self.preferred_speed;
                let ny = (rng.random() - 0.5) * self.preferred_speed;
                let p = [
                    self.circle_radius * angle.cos() + nx,
                    self.circle_radius * angle.sin() + ny,
                ];
                let near = |q: [f64; 2], r: f64| {
                    (p[0] - q[0]).hypot(p[1] - q[1]) < self.radius + r + self.discomfort_dist
                };
                if !placed
                    .iter()
                    .any(|&(at, goal, r)| near(at, r) || near(goal, r))
                {
                    break p;
                }
            };
            let goal = [-start[0], -start[1]];
            placed.push((start, goal, self.radius));
            people.push(Placed { start, goal });
        }
        people
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_generator_draws_numpy_s_numbers_for_a_seed() {
        // np.random.seed(0); np.random.random(3)
        let mut rng = Mt19937::new(0);
        let got = [rng.random(), rng.random(), rng.random()];
        assert_eq!(
            got,
            [0.5488135039273248, 0.7151893663724195, 0.6027633760716439]
        );
        // The reference implementation's first output for its default seed.
        assert_eq!(Mt19937::new(5489).next_u32(), 3_499_211_612);
    }

    #[test]
    fn circle_crossing_people_start_near_the_circle_apart_and_cross_it() {
        let c = CircleCrossing::default();
        for seed in TEST_SEED_OFFSET..TEST_SEED_OFFSET + 50 {
            let people = c.people(seed);
            assert_eq!(people.len(), 5);
            for (i, p) in people.iter().enumerate() {
                // On the circle but for the noise (at most 0.5 per axis).
                let r = p.start[0].hypot(p.start[1]);
                assert!((r - 4.0).abs() <= 0.5f64.hypot(0.5) + 1e-12, "{seed}: {r}");
                assert_eq!(p.goal, [-p.start[0], -p.start[1]]);
                let clear =
                    |q: [f64; 2], min: f64| (p.start[0] - q[0]).hypot(p.start[1] - q[1]) >= min;
                assert!(
                    clear(c.robot_start, 0.8) && clear(c.robot_goal, 0.8),
                    "{seed}: {p:?}"
                );
                for q in &people[..i] {
                    assert!(
                        clear(q.start, 0.8) && clear(q.goal, 0.8),
                        "{seed}: {p:?} {q:?}"
                    );
                }
            }
        }
        // Seeds give other cases.
        assert_ne!(c.people(1000), c.people(1001));
    }
}
