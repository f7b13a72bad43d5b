//! The material interface: what a wall does to light that reaches it, as
//! a BSDF with `eval`, `pdf`, `sample` and `is_specular`.
//!
//! Flatland's BSDF is per radian: a Lambertian wall of albedo `rho`
//! reflects `f = rho / 2`, since `∫ cos(theta) dtheta` over the half
//! circle is 2. A mirror, a transparent wall and a glass edge are
//! specular (delta) BSDFs: `eval` and `pdf` are zero for every given pair
//! of directions, and `sample` returns the one direction with its weight.
//!
//! Both integrators walk their paths through [`Bsdf::sample`]; the path
//! tracer's next-event estimation uses [`Bsdf::eval`] at non-specular
//! vertices. The wall memo stores irradiance, which only a Lambertian
//! wall turns into outgoing light by one factor: the path tracer reads it
//! only where [`Bsdf::lambertian`] says so.

use std::f64::consts::PI;

use flatray_geometry::{DVec2, Side, reflect};

use crate::glass::{GlassState, interact};
use crate::sampling::{Stream, cosine_half_circle, uniform_half_circle};
use crate::scene::{Material, Scene};
use crate::{Rgb, Stats};

/// The BSDF at one wall point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Bsdf {
    /// Lambertian reflection of albedo `rho`.
    Lambertian { rho: Rgb },
    /// Perfect specular reflection.
    Mirror { tint: Rgb },
    /// Straight through, multiplied by `tint`: not a scattering event
    /// (no bounce is counted).
    Transparent { tint: Rgb },
    /// Fresnel reflection or Snell refraction at an edge of glass body
    /// `body`, whose inside is on side `inside`.
    Glass { body: u32, inside: Side },
}

/// How a diffuse direction is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Sampling {
    /// Cosine-weighted: pdf `cos / 2`, weight exactly `rho`.
    Cosine,
    /// Uniform on the half circle (the original project's bounce): pdf
    /// `1 / pi`, weight `rho (pi / 2) cos`.
    Uniform,
}

/// What flows along a path: radiance, from a receiver (the path tracer),
/// or power, from a light (the light tracer). Refraction scales radiance
/// but conserves power.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Transport {
    Radiance,
    Power,
}

/// A direction drawn by [`Bsdf::sample`], and the factor the path's
/// throughput takes: `f cos / pdf` (for a specular event, the event's own
/// factor).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scattered {
    pub dir: DVec2,
    pub weight: Rgb,
}

impl Bsdf {
    /// The BSDF of wall `index` at `x`, the point at `u` of it. A diffuse
    /// wall without an albedo of its own takes the floor's there (counted
    /// in `stats`; with `tables`, from the table along the walls).
    #[inline]
    pub fn at(
        scene: &Scene,
        material: Material,
        (index, u, x): (u32, f64, DVec2),
        tables: bool,
        stats: &mut Stats,
    ) -> Bsdf {
        match material {
            Material::Diffuse { albedo } => Bsdf::Lambertian {
                rho: diffuse_albedo(scene, albedo, (index, u, x), tables, stats),
            },
            Material::Mirror { tint } => Bsdf::Mirror { tint },
            Material::Transparent { tint } => Bsdf::Transparent { tint },
            Material::Glass { body, inside } => Bsdf::Glass { body, inside },
        }
    }

    /// Whether the BSDF is a delta: no light arrives through `eval`, so
    /// next-event estimation is pointless there.
    #[inline]
    pub fn is_specular(&self) -> bool {
        match self {
            Bsdf::Lambertian { .. } => false,
            Bsdf::Mirror { .. } | Bsdf::Transparent { .. } | Bsdf::Glass { .. } => true,
        }
    }

    /// The albedo of a Lambertian BSDF: the one case where the outgoing
    /// light is the irradiance times one factor (`rho / 2`), which the
    /// wall memo relies on.
    #[inline]
    pub fn lambertian(&self) -> Option<Rgb> {
        match *self {
            Bsdf::Lambertian { rho } => Some(rho),
            Bsdf::Mirror { .. } | Bsdf::Transparent { .. } | Bsdf::Glass { .. } => None,
        }
    }

    /// `f(wo, wi)` per radian for light arriving from `wi` and leaving
    /// towards `wo`, both unit directions pointing away from the wall,
    /// whose unit normal on the side the path is on is `n`. With
    /// [`Bsdf::pdf`], what an estimator that joins two paths, or weighs
    /// strategies, needs; today's integrators read a Lambertian's constant
    /// through [`Bsdf::lambertian`], and the tests hold `sample` to these.
    #[allow(dead_code)]
    #[inline]
    pub fn eval(&self, n: DVec2, wo: DVec2, wi: DVec2) -> Rgb {
        match *self {
            Bsdf::Lambertian { rho } => {
                if n.dot(wo) > 0.0 && n.dot(wi) > 0.0 {
                    rho * 0.5
                } else {
                    Rgb::ZERO
                }
            }
            Bsdf::Mirror { .. } | Bsdf::Transparent { .. } | Bsdf::Glass { .. } => Rgb::ZERO,
        }
    }

    /// The density per radian with which [`Bsdf::sample`] draws `wi`.
    #[allow(dead_code)]
    #[inline]
    pub fn pdf(&self, n: DVec2, wi: DVec2, sampling: Sampling) -> f64 {
        match *self {
            Bsdf::Lambertian { .. } => {
                let cos = n.dot(wi);
                if cos <= 0.0 {
                    0.0
                } else {
                    match sampling {
                        Sampling::Cosine => 0.5 * cos,
                        Sampling::Uniform => 1.0 / PI,
                    }
                }
            }
            Bsdf::Mirror { .. } | Bsdf::Transparent { .. } | Bsdf::Glass { .. } => 0.0,
        }
    }

    /// A direction for a path that arrived travelling along `dir` on side
    /// `arrival` of a wall with unit normal `n` on that side, and the
    /// throughput's factor. Glass draws from `stream` and updates `glass`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn sample(
        &self,
        scene: &Scene,
        (dir, n, arrival): (DVec2, DVec2, Side),
        sampling: Sampling,
        transport: Transport,
        glass: &mut GlassState,
        stream: &mut Stream,
        stats: &mut Stats,
    ) -> Scattered {
        match *self {
            Bsdf::Lambertian { rho } => match sampling {
                Sampling::Cosine => Scattered {
                    // f cos / pdf = (rho / 2) cos / (cos / 2): exactly rho.
                    dir: cosine_half_circle(n, stream.uniform()),
                    weight: rho,
                },
                Sampling::Uniform => {
                    // f cos / pdf = (rho / 2) cos pi.
                    let (dir, cos) = uniform_half_circle(n, stream.uniform());
                    Scattered {
                        dir,
                        weight: rho * (0.5 * PI * cos),
                    }
                }
            },
            Bsdf::Mirror { tint } => Scattered {
                dir: reflect(dir, n),
                weight: tint,
            },
            Bsdf::Transparent { tint } => Scattered { dir, weight: tint },
            Bsdf::Glass { body, inside } => {
                let event = interact(scene, body, inside, arrival, dir, n, glass, stream, stats);
                let weight = match transport {
                    Transport::Radiance => event.colour * event.radiance_scale,
                    Transport::Power => event.colour,
                };
                Scattered {
                    dir: event.dir,
                    weight,
                }
            }
        }
    }
}

/// A diffuse wall's albedo at `x`, the point at `u` on wall `wall`: its
/// own, or the floor's there (colour bleeding from the floor), counted in
/// `stats`; with `tables`, read from the table along the walls.
#[inline]
pub(crate) fn diffuse_albedo(
    scene: &Scene,
    albedo: Option<Rgb>,
    (wall, u, x): (u32, f64, DVec2),
    tables: bool,
    stats: &mut Stats,
) -> Rgb {
    match albedo {
        Some(rho) => rho,
        None => {
            stats.work.floor_albedo_reads += 1;
            if tables {
                scene
                    .albedo_along
                    .at(&scene.floor, &scene.canvas, wall, u, x)
            } else {
                scene.floor.albedo_at(&scene.canvas, x)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Stream;
    use crate::scene::{Canvas, Floor};

    fn scene() -> Scene {
        let canvas = Canvas {
            width: 4,
            height: 4,
            origin: DVec2::ZERO,
        };
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, Vec::new(), Vec::new())
    }

    /// For the Lambertian BSDF, `sample`'s weight is `f cos / pdf` with
    /// `eval` and `pdf`, for both strategies, and `f` integrates to `rho`
    /// against the cosine (energy conservation, flatland's factor 2).
    #[test]
    fn a_lambertian_samples_what_it_evaluates() {
        let scene = scene();
        let rho = Rgb::new(0.8, 0.5, 0.2);
        let bsdf = Bsdf::Lambertian { rho };
        let n = DVec2::new(0.6, -0.8);
        let wo = DVec2::new(0.0, -1.0);
        let mut stream = Stream::new(3, 4, 5);
        let (mut glass, mut stats) = (GlassState::default(), Stats::default());
        for sampling in [Sampling::Cosine, Sampling::Uniform] {
            for _ in 0..1000 {
                let s = bsdf.sample(
                    &scene,
                    (-wo, n, Side::Positive),
                    sampling,
                    Transport::Radiance,
                    &mut glass,
                    &mut stream,
                    &mut stats,
                );
                let cos = n.dot(s.dir);
                assert!(cos > 0.0);
                let expected = bsdf.eval(n, wo, s.dir) * cos / bsdf.pdf(n, s.dir, sampling);
                assert!((s.weight - expected).abs().max_element() < 1e-12 * (1.0 + 1.0 / cos));
            }
        }
        // ∫ f cos dtheta over the half circle, by a midpoint rule.
        let m = 100_000;
        let sum: Rgb = (0..m)
            .map(|k| {
                let theta = PI * ((k as f64 + 0.5) / m as f64 - 0.5);
                let wi = n * theta.cos() + n.perp() * theta.sin();
                bsdf.eval(n, wo, wi) * theta.cos() * (PI / m as f64)
            })
            .sum();
        assert!((sum - rho).abs().max_element() < 1e-9, "{sum}");
        // Nothing through the wall.
        assert_eq!(bsdf.eval(n, wo, -n), Rgb::ZERO);
        assert_eq!(bsdf.pdf(n, -n, Sampling::Cosine), 0.0);
    }

    #[test]
    fn specular_bsdfs_evaluate_to_nothing_and_sample_their_one_direction() {
        let scene = scene();
        let n = DVec2::new(0.0, 1.0);
        let dir = DVec2::new(0.6, -0.8);
        let mut stream = Stream::new(1, 1, 1);
        let (mut glass, mut stats) = (GlassState::default(), Stats::default());
        let tint = Rgb::new(0.9, 0.8, 0.7);
        for (bsdf, expected) in [
            (Bsdf::Mirror { tint }, DVec2::new(0.6, 0.8)),
            (Bsdf::Transparent { tint }, dir),
        ] {
            assert!(bsdf.is_specular());
            assert_eq!(bsdf.eval(n, -dir, expected), Rgb::ZERO);
            assert_eq!(bsdf.pdf(n, expected, Sampling::Cosine), 0.0);
            let s = bsdf.sample(
                &scene,
                (dir, n, Side::Positive),
                Sampling::Cosine,
                Transport::Radiance,
                &mut glass,
                &mut stream,
                &mut stats,
            );
            assert!((s.dir - expected).length() < 1e-15);
            assert_eq!(s.weight, tint);
        }
        assert!(!Bsdf::Lambertian { rho: Rgb::ONE }.is_specular());
    }
}
