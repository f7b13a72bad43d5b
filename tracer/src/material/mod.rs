//! The material interface: what a wall does to light that reaches it, as
//! a BSDF with `eval`, `pdf`, `sample` and `is_specular`. A material is
//! defined with the scene ([`Material`]); here is what it does to light,
//! and nothing outside this module matches its kind.
//!
//! Flatland's BSDF is per radian: a Lambertian wall of albedo `rho`
//! reflects `f = rho / 2`, since `∫ cos(theta) dtheta` over the half
//! circle is 2. A rough mirror reflects a glossy lobe about the mirror
//! direction (`rough.rs`). A mirror, a transparent wall and a glass edge
//! are specular (delta) BSDFs: `eval` and `pdf` are zero for every given
//! pair of directions, and `sample` returns the one direction with its
//! weight.
//!
//! Both integrators walk their paths through [`Bsdf::sample`]. The path
//! tracer's next-event estimation at a non-specular vertex takes `f`
//! from [`Bsdf::eval`]: where `f` is one constant ([`Bsdf::lambertian`]),
//! it is `f` times the irradiance, which the wall memo and the caustic
//! pass store; elsewhere (a glossy lobe) each light's sample is weighed by
//! `eval` and, against the lobe's own samples, by [`Bsdf::pdf`] (multiple
//! importance sampling, `direct::direct_light_glossy`).

pub(crate) mod glass;
mod rough;

use std::f64::consts::PI;

use flatray_geometry::{DVec2, Side, reflect};

use crate::sampling::{Stream, cosine_half_circle, uniform_half_circle};
use crate::scene::{Material, Scene};
use crate::{Rgb, Stats};
use glass::{GlassState, interact};

/// The BSDF at one wall point: the wall's material, with the colour it
/// takes there (a diffuse wall's albedo, which may be the floor's; a
/// mirror's or a pane's tint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bsdf {
    material: Material,
    colour: Rgb,
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
    #[inline(always)]
    pub fn at(
        scene: &Scene,
        material: Material,
        (index, u, x): (u32, f64, DVec2),
        tables: bool,
        stats: &mut Stats,
    ) -> Bsdf {
        let colour = match material {
            Material::Diffuse { albedo } => {
                diffuse_albedo(scene, albedo, (index, u, x), tables, stats)
            }
            Material::Mirror { tint }
            | Material::Rough { tint, .. }
            | Material::Transparent { tint } => tint,
            Material::Glass { .. } => Rgb::ONE,
        };
        Bsdf { material, colour }
    }

    /// Whether the BSDF is a delta: no light arrives through `eval`, so
    /// next-event estimation is pointless there.
    #[inline]
    pub fn is_specular(&self) -> bool {
        match self.material {
            Material::Diffuse { .. } | Material::Rough { .. } => false,
            Material::Mirror { .. } | Material::Transparent { .. } | Material::Glass { .. } => true,
        }
    }

    /// Whether light goes on straight through, unturned: no scattering
    /// event (a pane).
    #[inline]
    pub fn is_straight(&self) -> bool {
        matches!(self.material, Material::Transparent { .. })
    }

    /// Whether the BSDF is the perfect mirror (counted in the statistics,
    /// and the rays off it culled by direction).
    #[inline]
    pub fn is_mirror(&self) -> bool {
        matches!(self.material, Material::Mirror { .. })
    }

    /// Whether the BSDF is non-specular and its `f` depends on the
    /// directions: next-event estimation then weighs each light by `eval`,
    /// and its own samples against the lights' by multiple importance
    /// sampling.
    #[inline]
    pub fn is_glossy(&self) -> bool {
        matches!(self.material, Material::Rough { .. })
    }

    /// The albedo of a Lambertian BSDF, whose `eval` is `rho / 2` for
    /// every pair of directions on its side: the one case where the
    /// outgoing light is the irradiance times one factor, which the wall
    /// memo and the caustic pass rely on.
    #[inline]
    pub fn lambertian(&self) -> Option<Rgb> {
        match self.material {
            Material::Diffuse { .. } => Some(self.colour),
            _ => None,
        }
    }

    /// `f(wo, wi)` per radian for light arriving from `wi` and leaving
    /// towards `wo`, both unit directions pointing away from the wall,
    /// whose unit normal on the side the path is on is `n`. Zero where
    /// either direction is behind the wall, and for a delta BSDF.
    #[inline]
    pub fn eval(&self, n: DVec2, wo: DVec2, wi: DVec2) -> Rgb {
        let (so, co) = rough::sine_cosine(n, wo);
        let (si, ci) = rough::sine_cosine(n, wi);
        if co <= 0.0 || ci <= 0.0 {
            return Rgb::ZERO;
        }
        match self.material {
            Material::Diffuse { .. } => self.colour * 0.5,
            Material::Rough { roughness, .. } => self.colour * rough::density(roughness, so, si),
            Material::Mirror { .. } | Material::Transparent { .. } | Material::Glass { .. } => {
                Rgb::ZERO
            }
        }
    }

    /// The density per radian with which [`Bsdf::sample`] draws `wi` for
    /// a path leaving towards `wo` (both pointing away from the wall).
    #[inline]
    pub fn pdf(&self, n: DVec2, wo: DVec2, wi: DVec2, sampling: Sampling) -> f64 {
        let (so, co) = rough::sine_cosine(n, wo);
        let (si, ci) = rough::sine_cosine(n, wi);
        if ci <= 0.0 {
            return 0.0;
        }
        match self.material {
            Material::Diffuse { .. } => match sampling {
                Sampling::Cosine => 0.5 * ci,
                Sampling::Uniform => 1.0 / PI,
            },
            // ds = cos dtheta: the density in the sine, per radian.
            Material::Rough { roughness, .. } if co > 0.0 => rough::density(roughness, so, si) * ci,
            Material::Rough { .. }
            | Material::Mirror { .. }
            | Material::Transparent { .. }
            | Material::Glass { .. } => 0.0,
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
        let colour = self.colour;
        match self.material {
            Material::Diffuse { .. } => match sampling {
                Sampling::Cosine => Scattered {
                    // f cos / pdf = (rho / 2) cos / (cos / 2): exactly rho.
                    dir: cosine_half_circle(n, stream.uniform()),
                    weight: colour,
                },
                Sampling::Uniform => {
                    // f cos / pdf = (rho / 2) cos pi.
                    let (dir, cos) = uniform_half_circle(n, stream.uniform());
                    Scattered {
                        dir,
                        weight: colour * (0.5 * PI * cos),
                    }
                }
            },
            Material::Rough { roughness, .. } => {
                // The lobe is drawn exactly: f cos / pdf is the tint.
                let (so, _) = rough::sine_cosine(n, -dir);
                let u = (stream.uniform(), stream.uniform());
                let si = rough::sample(roughness, so, u);
                Scattered {
                    dir: rough::direction(n, si),
                    weight: colour,
                }
            }
            Material::Mirror { .. } => Scattered {
                dir: reflect(dir, n),
                weight: colour,
            },
            Material::Transparent { .. } => Scattered {
                dir,
                weight: colour,
            },
            Material::Glass { body, inside } => {
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

    fn of(material: Material) -> Bsdf {
        Bsdf::at(
            &scene(),
            material,
            (0, 0.5, DVec2::ZERO),
            false,
            &mut Stats::default(),
        )
    }

    fn lambertian(rho: Rgb) -> Bsdf {
        of(Material::Diffuse { albedo: Some(rho) })
    }

    fn scene() -> Scene {
        let canvas = Canvas {
            width: 4,
            height: 4,
            origin: DVec2::ZERO,
        };
        Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, Vec::new(), Vec::new())
            .expect("a valid scene")
    }

    /// For the Lambertian BSDF, `sample`'s weight is `f cos / pdf` with
    /// `eval` and `pdf`, for both strategies, and `f` integrates to `rho`
    /// against the cosine (energy conservation, flatland's factor 2).
    #[test]
    fn a_lambertian_samples_what_it_evaluates() {
        let scene = scene();
        let rho = Rgb::new(0.8, 0.5, 0.2);
        let bsdf = lambertian(rho);
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
                let expected = bsdf.eval(n, wo, s.dir) * cos / bsdf.pdf(n, wo, s.dir, sampling);
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
        assert_eq!(bsdf.pdf(n, wo, -n, Sampling::Cosine), 0.0);
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
            (of(Material::Mirror { tint }), DVec2::new(0.6, 0.8)),
            (of(Material::Transparent { tint }), dir),
        ] {
            assert!(bsdf.is_specular());
            assert_eq!(bsdf.eval(n, -dir, expected), Rgb::ZERO);
            assert_eq!(bsdf.pdf(n, -dir, expected, Sampling::Cosine), 0.0);
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
        assert!(!lambertian(Rgb::ONE).is_specular());
    }

    /// For the rough mirror, `sample`'s weight is `f cos / pdf` with
    /// `eval` and `pdf`, and its directions follow `pdf`: a chi-square
    /// test over 20 bins of angle (19 degrees of freedom, the 0.1 %
    /// critical value 43.82), for several roughnesses and arrivals. `eval`
    /// is reciprocal.
    #[test]
    fn a_rough_mirror_samples_what_it_evaluates() {
        let scene = scene();
        let tint = Rgb::new(0.9, 0.7, 0.5);
        let n = DVec2::new(0.6, -0.8);
        let t = n.perp();
        let mut stream = Stream::new(11, 12, 13);
        let (mut glass, mut stats) = (GlassState::default(), Stats::default());
        for (roughness, arrival) in [(0.05, 0.3), (0.2, -1.2), (0.6, 1.4), (1.0, 0.0)] {
            let bsdf = of(Material::Rough { roughness, tint });
            assert!(!bsdf.is_specular() && bsdf.is_glossy());
            // The direction the path arrives from, at `arrival` radians.
            let wo = n * f64::cos(arrival) + t * f64::sin(arrival);
            let bins = 20;
            let draws = 200_000;
            let mut counts = vec![0.0; bins];
            for _ in 0..draws {
                let s = bsdf.sample(
                    &scene,
                    (-wo, n, Side::Positive),
                    Sampling::Cosine,
                    Transport::Radiance,
                    &mut glass,
                    &mut stream,
                    &mut stats,
                );
                let cos = n.dot(s.dir);
                assert!(cos >= 0.0);
                if cos > 1e-6 {
                    let expected =
                        bsdf.eval(n, wo, s.dir) * cos / bsdf.pdf(n, wo, s.dir, Sampling::Cosine);
                    assert!(
                        (s.weight - expected).abs().max_element() < 1e-9,
                        "{roughness}"
                    );
                }
                let theta = t.dot(s.dir).atan2(cos);
                let b = (((theta / PI + 0.5) * bins as f64) as usize).min(bins - 1);
                counts[b] += 1.0;
            }
            let mut chi2 = 0.0;
            for (b, &count) in counts.iter().enumerate() {
                let steps = 2000;
                let p: f64 = (0..steps)
                    .map(|k| {
                        let theta =
                            PI * ((b as f64 + (k as f64 + 0.5) / steps as f64) / bins as f64 - 0.5);
                        let wi = n * theta.cos() + t * theta.sin();
                        bsdf.pdf(n, wo, wi, Sampling::Cosine) * PI / (bins * steps) as f64
                    })
                    .sum();
                let expected = p * draws as f64;
                chi2 += (count - expected) * (count - expected) / expected.max(1.0);
            }
            assert!(
                chi2 < 43.82,
                "roughness {roughness}, arrival {arrival}: chi2 {chi2}"
            );
            // Reciprocal, and zero behind the wall.
            let wi = n * 0.8 + t * 0.6;
            let (a, b) = (bsdf.eval(n, wo, wi), bsdf.eval(n, wi, wo));
            assert!((a - b).abs().max_element() < 1e-12 * a.max_element().max(1.0));
            assert_eq!(bsdf.eval(n, wo, -n), Rgb::ZERO);
            assert_eq!(bsdf.pdf(n, wo, -wi, Sampling::Cosine), 0.0);
        }
    }
}
