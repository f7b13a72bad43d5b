//! Error of an image against a reference, and the log-log fits that turn
//! a convergence study into numbers.

use crate::Image;

/// How far an image is from a reference, over every pixel and channel, in
/// linear values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageError {
    /// Root mean square of the difference.
    pub rmse: f64,
    /// `rmse` divided by the reference's root mean square value.
    pub relative_rmse: f64,
    /// Mean of the difference: an estimate of the bias.
    pub mean_error: f64,
    /// The root of the relative mean squared error (relMSE, Rousselle et
    /// al. 2011): each pixel's and channel's squared difference over the
    /// square of the reference's value there, floored at
    /// [`RELMSE_FLOOR`], averaged over pixels and channels. It weighs a
    /// dark pixel's error by its own value, as the eye does, where
    /// `relative_rmse` weighs every error by the image's bright parts.
    pub relmse: f64,
}

/// The floor under a reference value in relMSE's denominator, in image
/// units (1 is a well-lit floor): the error of a pixel darker than this
/// is measured against this, so that black pixels do not divide by zero.
pub const RELMSE_FLOOR: f64 = 0.03;

/// A pixel channel's squared error `error_squared` relative to the
/// square of its value `value`, floored at [`RELMSE_FLOOR`].
#[inline]
pub fn relative_squared(error_squared: f64, value: f64) -> f64 {
    error_squared / (value * value).max(RELMSE_FLOOR * RELMSE_FLOOR)
}

/// The error of `image` against `reference`, or `None` when their sizes
/// differ or the reference is black.
pub fn compare(image: &Image, reference: &Image) -> Option<ImageError> {
    if image.width != reference.width || image.height != reference.height {
        return None;
    }
    let (mut sq, mut diff, mut ref_sq, mut relative) = (0.0, 0.0, 0.0, 0.0);
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            sq += d * d;
            diff += d;
            ref_sq += (b[c] as f64).powi(2);
            relative += relative_squared(d * d, b[c] as f64);
        }
    }
    let n = (image.pixels.len() * 3) as f64;
    let rms_ref = (ref_sq / n).sqrt();
    if rms_ref <= 0.0 || n == 0.0 {
        return None;
    }
    let rmse = (sq / n).sqrt();
    Some(ImageError {
        rmse,
        relative_rmse: rmse / rms_ref,
        mean_error: diff / n,
        relmse: (relative / n).sqrt(),
    })
}

/// The least-squares slope of `log(y)` against `log(x)`, over points with
/// positive coordinates; `None` with fewer than two.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The first `x` at which `y` falls to `target`, interpolating linearly in
/// log-log between consecutive points (sorted by `x`); `None` if it never
/// does. A first point already below the target gives that point's `x`.
pub fn reach(points: &[(f64, f64)], target: f64) -> Option<f64> {
    let first = points.first()?;
    if first.1 <= target {
        return Some(first.0);
    }
    for pair in points.windows(2) {
        let ((x0, y0), (x1, y1)) = (pair[0], pair[1]);
        if y1 <= target && y0 > target && x0 > 0.0 && x1 > 0.0 && y1 > 0.0 {
            let f = (target.ln() - y0.ln()) / (y1.ln() - y0.ln());
            return Some((x0.ln() + f * (x1.ln() - x0.ln())).exp());
        }
    }
    None
}

/// Which figure of error `--target-error`, `--time`'s report and
/// `converge`'s table aim at.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ErrorMetric {
    /// The root of relMSE ([`ImageError::relmse`], [`crate::Noise::relmse`]):
    /// every pixel's error relative to its own value, so that dark
    /// regions count as much as bright ones.
    #[default]
    RelMse,
    /// The relative RMS error ([`ImageError::relative_rmse`],
    /// [`crate::Noise::relative`]): the image's RMS error over its RMS
    /// value, which its bright regions dominate.
    Rms,
}

impl ErrorMetric {
    /// The metric's name, as the command line and the reports write it.
    pub fn name(self) -> &'static str {
        match self {
            ErrorMetric::RelMse => "relMSE",
            ErrorMetric::Rms => "relative RMSE",
        }
    }

    /// A render's estimate of its own error by this metric.
    pub fn of_noise(self, noise: &crate::Noise) -> Option<f64> {
        match self {
            ErrorMetric::RelMse => noise.relmse(),
            ErrorMetric::Rms => noise.relative(),
        }
    }

    /// An image's error against a reference by this metric.
    pub fn of_error(self, error: &ImageError) -> f64 {
        match self {
            ErrorMetric::RelMse => error.relmse,
            ErrorMetric::Rms => error.relative_rmse,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_a_power_law_is_its_exponent() {
        let points: Vec<(f64, f64)> = (0..8)
            .map(|k| (2f64.powi(k), 3.0 * 2f64.powi(k).powf(-0.5)))
            .collect();
        assert!((log_log_slope(&points).unwrap() + 0.5).abs() < 1e-12);
    }

    #[test]
    fn reach_interpolates_in_log_log() {
        let points = [(1.0, 0.4), (4.0, 0.1), (16.0, 0.05)];
        assert_eq!(reach(&points, 0.5), Some(1.0));
        assert!((reach(&points, 0.2).unwrap() - 2.0).abs() < 1e-12);
        assert!((reach(&points, 0.1).unwrap() - 4.0).abs() < 1e-12);
        assert_eq!(reach(&points, 0.01), None);
    }

    #[test]
    fn compare_measures_rmse_and_bias() {
        let reference = Image {
            width: 2,
            height: 1,
            pixels: vec![[1.0; 3], [3.0; 3]],
        };
        let image = Image {
            width: 2,
            height: 1,
            pixels: vec![[2.0; 3], [3.0; 3]],
        };
        let e = compare(&image, &reference).unwrap();
        assert!((e.rmse - 0.5f64.sqrt()).abs() < 1e-12);
        assert!((e.relative_rmse - 0.5f64.sqrt() / 5f64.sqrt()).abs() < 1e-12);
        assert!((e.mean_error - 0.5).abs() < 1e-12);
        assert!(compare(&Image::new(1, 1), &reference).is_none());
    }

    /// relMSE weighs each pixel's error by its own value (floored), the
    /// relative RMSE by the image's: a 10 % error on a dark pixel beside a
    /// bright exact one is 7 % relMSE and 0.3 % relative RMSE.
    #[test]
    fn relmse_weighs_each_pixel_by_its_own_value() {
        let mut reference = Image::new(2, 1);
        reference.pixels = vec![[4.0; 3], [0.1; 3]];
        let mut image = reference.clone();
        image.pixels[1] = [0.11; 3];
        let e = compare(&image, &reference).unwrap();
        // Half the pixels 10 % off: the root of (0.01 / 2).
        assert!((e.relmse - 0.005f64.sqrt()).abs() < 1e-6, "{e:?}");
        let rms = (0.01f64 * 0.01 / 2.0).sqrt() / ((16.0 + 0.01) / 2.0f64).sqrt();
        assert!((e.relative_rmse - rms).abs() < 1e-6, "{e:?}");
        assert_eq!(ErrorMetric::RelMse.of_error(&e), e.relmse);
        assert_eq!(ErrorMetric::Rms.of_error(&e), e.relative_rmse);
        // Below the floor a pixel's error counts against the floor.
        let mut black = Image::new(1, 1);
        black.pixels = vec![[0.0, 0.0, 1.0]];
        let mut off = black.clone();
        off.pixels[0] = [RELMSE_FLOOR as f32, 0.0, 1.0];
        let e = compare(&off, &black).unwrap();
        assert!((e.relmse - (1.0f64 / 3.0).sqrt()).abs() < 1e-6, "{e:?}");
    }
}
