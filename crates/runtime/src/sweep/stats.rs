//! The statistics over a sweep's seeds: the mean with its 95 % interval
//! (Student's t), and the largest allowable value of a swept key.

/// The 0.975 quantile of Student's t with `df` degrees of freedom (exact
/// to 3 decimals from a table up to 30, Cornish-Fisher expansion beyond).
pub(super) fn t975(df: usize) -> f64 {
    const TABLE: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    match df {
        0 => f64::NAN,
        1..=30 => TABLE[df - 1],
        _ => {
            let z: f64 = 1.959_964;
            let n = df as f64;
            z + (z.powi(3) + z) / (4.0 * n)
                + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * n * n)
        }
    }
}

/// Mean and the half-width of its 95 % interval (None with fewer than two
/// values for the interval, or none at all for the mean).
pub fn mean_ci(xs: &[f64]) -> (Option<f64>, Option<f64>) {
    if xs.is_empty() {
        return (None, None);
    }
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    if xs.len() < 2 {
        return (Some(mean), None);
    }
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (Some(mean), Some(t975(xs.len() - 1) * (var / n).sqrt()))
}

/// The largest value of `key` that is allowable for one seed: the largest
/// tested value whose run had no collision (0 if every value collided).
pub fn largest_allowable(runs: &[(f64, bool)]) -> f64 {
    runs.iter()
        .filter(|(_, collided)| !collided)
        .map(|(v, _)| *v)
        .fold(0.0, f64::max)
}
