//! Glass optics: Fresnel reflectance, Cauchy dispersion, and wavelengths
//! turned into RGB.

use flatray_geometry::{DVec2, reflect, refract};

use crate::Rgb;

/// The reflected fraction of unpolarised light at an interface from index
/// `n1` into `n2`, at incidence cosine `cos_i`; 1 beyond the critical
/// angle. The mean of the s and p reflectances (in the plane both
/// polarisations exist, as in 3D); the rest is transmitted, so reflected
/// plus transmitted is exactly the incoming power.
pub fn fresnel(n1: f64, n2: f64, cos_i: f64) -> f64 {
    let cos_i = cos_i.abs().min(1.0);
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    0.5 * (rs * rs + rp * rp)
}

/// The choice at an edge between indices `n1` (the side the ray comes
/// from) and `n2`: reflection with probability `F = fresnel(...)`, else
/// refraction, decided by `u` uniform in `[0, 1)`. Returns the new
/// direction and whether it reflected. Each outcome carries the full
/// power, so the expected power leaving is `F + (1 - F) = 1`: exactly the
/// incoming power, for clear glass.
pub fn choose(n1: f64, n2: f64, dir: DVec2, normal: DVec2, u: f64) -> (DVec2, bool) {
    let reflectance = fresnel(n1, n2, dir.dot(normal));
    if u >= reflectance
        && let Some(t) = refract(dir, normal, n1 / n2)
    {
        return (t, false);
    }
    (reflect(dir, normal), true)
}

/// The wavelength (micrometres) at which a glass's `ior` is given.
pub const REFERENCE_WAVELENGTH: f64 = 0.55;

/// Cauchy's formula `n(l) = A + B / l^2` (`l` in micrometres), with `A`
/// chosen so that `n(0.55) = ior`.
pub fn cauchy(ior: f64, b: f64, wavelength_um: f64) -> f64 {
    ior - b / (REFERENCE_WAVELENGTH * REFERENCE_WAVELENGTH) + b / (wavelength_um * wavelength_um)
}

/// The visible range sampled by dispersive scenes, in micrometres.
pub const VISIBLE: (f64, f64) = (
    crate::spectrum::RANGE_NM.0 / 1000.0,
    crate::spectrum::RANGE_NM.1 / 1000.0,
);

/// The RGB weight of a wavelength (micrometres) drawn uniformly from
/// [`VISIBLE`]: the CIE 1931 colour matching functions in linear sRGB,
/// divided channel by channel by their mean over the range, so that
/// their mean is exactly (1, 1, 1) (`crate::spectrum::wavelength_rgb`).
/// White light split into wavelengths and recombined is white again.
pub fn wavelength_rgb(wavelength_um: f64) -> Rgb {
    crate::spectrum::wavelength_rgb(wavelength_um * 1000.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_reflects_the_closed_form_fraction() {
        for (n1, n2) in [(1.0f64, 1.5f64), (1.5, 1.0), (1.0, 2.4), (1.33, 1.0)] {
            let expected = ((n1 - n2) / (n1 + n2)).powi(2);
            assert!(
                (fresnel(n1, n2, 1.0) - expected).abs() < 1e-15,
                "{n1} -> {n2}"
            );
        }
    }

    #[test]
    fn beyond_the_critical_angle_everything_reflects() {
        let critical = (1.0f64 / 1.5).asin();
        assert_eq!(fresnel(1.5, 1.0, (critical + 1e-6).cos()), 1.0);
        assert!(fresnel(1.5, 1.0, (critical - 1e-3).cos()) < 1.0);
        // Grazing incidence from air reflects nearly everything too.
        assert!(fresnel(1.0, 1.5, 1e-9) > 0.999);
    }

    #[test]
    fn reflectance_is_a_fraction_and_symmetric_in_the_path() {
        // Reciprocity: the same reflectance from either side at matching
        // angles (Stokes), and always within [0, 1].
        for k in 0..=89 {
            let i = (k as f64).to_radians();
            let r = fresnel(1.0, 1.5, i.cos());
            assert!((0.0..=1.0).contains(&r));
            let t = (i.sin() / 1.5).asin();
            assert!((fresnel(1.5, 1.0, t.cos()) - r).abs() < 1e-12, "{k}");
        }
    }

    #[test]
    fn cauchy_gives_the_ior_at_the_reference_and_more_in_the_blue() {
        assert!((cauchy(1.5, 0.01, 0.55) - 1.5).abs() < 1e-15);
        assert!(cauchy(1.5, 0.01, 0.45) > cauchy(1.5, 0.01, 0.65));
    }

    #[test]
    fn wavelength_weights_average_to_white() {
        let n = 10_000;
        let (lo, hi) = VISIBLE;
        let mut sum = Rgb::ZERO;
        for k in 0..n {
            sum += wavelength_rgb(lo + (hi - lo) * (k as f64 + 0.5) / n as f64);
        }
        let mean = sum / n as f64;
        assert!((mean - Rgb::ONE).abs().max_element() < 1e-4, "{mean}");
        assert!(wavelength_rgb(0.45).z > wavelength_rgb(0.45).x);
        assert!(wavelength_rgb(0.65).x > wavelength_rgb(0.65).z);
    }
}
