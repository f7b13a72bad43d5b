//! What a path or a photon does at a glass edge: Fresnel reflection or
//! Snell refraction, chosen with the Fresnel probability, with Cauchy
//! dispersion (a wavelength drawn at the first dispersive edge) and
//! Beer-Lambert absorption inside.
//!
//! **Rough glass** (a body's `roughness` above 0) spreads both the
//! reflected and the refracted light with the rough mirror's lobe
//! (`rough.rs`): the direction of arrival is turned by the lobe on its
//! side, the smooth event (Fresnel, Snell) takes the turned direction,
//! and the direction it leaves by is turned again by the lobe on its own
//! side. Each turn draws the sine of the direction from a Gaussian of
//! spread `roughness / sqrt(2)` about the sine it had, folded back into
//! `(-1, 1)` at grazing incidence: a kernel that is symmetric and
//! integrates to 1. So every event keeps the power it carries (the smooth
//! event does, and each turn does), and the whole event is reciprocal
//! (a symmetric turn, an event reciprocal in the sine times the index,
//! the same turn): light and path tracing see the same glass, with the
//! radiance factor `n1 / n2` of smooth glass. Roughness 0 is smooth glass
//! to the bit: no number is drawn for the turns.

use flatray_geometry::{DVec2, Side};

use super::rough;
use crate::optics::{cauchy, choose};
use crate::sampling::Stream;
use crate::scene::{Material, Scene};
use crate::{Rgb, Stats};

/// The glass state a path carries.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct GlassState {
    /// The body the path travels inside, if any.
    pub inside: Option<u32>,
    /// The wavelength (micrometres), once a dispersive edge drew one.
    pub wavelength: Option<f64>,
}

impl GlassState {
    /// The body a flight that ends at wall `material`, reached from side
    /// `arrival`, travelled inside: a glass edge reached from its inside
    /// says so exactly (this also covers a path that started inside glass);
    /// otherwise the tracked state.
    #[inline]
    pub fn flight_body(&self, material: &Material, arrival: Side) -> Option<u32> {
        match material.glass() {
            Some((body, inside)) if arrival == inside => Some(body),
            Some(_) => None,
            None => self.inside,
        }
    }
}

/// The Beer-Lambert absorption coefficients of `body` (zero for air).
#[inline]
pub(crate) fn absorption(scene: &Scene, body: Option<u32>) -> Rgb {
    body.map_or(Rgb::ZERO, |b| scene.glass[b as usize].absorption)
}

/// The Beer-Lambert transmittance over length `t` with coefficients `a`.
#[inline]
pub(crate) fn transmit(a: Rgb, t: f64) -> Rgb {
    if a == Rgb::ZERO {
        Rgb::ONE
    } else {
        Rgb::new((-a.x * t).exp(), (-a.y * t).exp(), (-a.z * t).exp())
    }
}

/// What an edge event returns.
pub(crate) struct Event {
    pub dir: DVec2,
    /// The colour factor: 1, or the RGB weight of a wavelength drawn here
    /// for the first time.
    pub colour: Rgb,
    /// `n1 / n2` for a refraction, 1 for a reflection: the factor by which
    /// radiance (not power) changes across the edge in flatland, which a
    /// path traced from the receiver must apply (`L / n` is invariant along
    /// a ray in 2D).
    pub radiance_scale: f64,
}

/// The spread of each of rough glass's two turns for a body of
/// `roughness`: two turns of `roughness / sqrt(2)` spread a reflection
/// about as much as a rough mirror of `roughness`.
#[inline]
fn turn_spread(roughness: f64) -> f64 {
    roughness * std::f64::consts::FRAC_1_SQRT_2
}

/// `w` turned by the lobe of spread `sigma` on the side of unit normal
/// `n` it points to: its sine drawn about its own sine, folded.
#[inline]
fn turn(sigma: f64, n: DVec2, w: DVec2, stream: &mut Stream) -> DVec2 {
    let n = if n.dot(w) < 0.0 { -n } else { n };
    let (s, _) = rough::sine_cosine(n, w);
    // `rough::sample` centres its lobe on the mirror of its sine.
    let u = (stream.uniform(), stream.uniform());
    rough::direction(n, rough::sample(sigma, -s, u))
}

/// Rough glass's event for a ray travelling along `dir` from index `n1`
/// into `n2` at an edge of unit normal `normal`: the direction of arrival
/// turned, the smooth event, the direction of leaving turned. Returns
/// the direction and whether the light stayed on its side (reflected).
fn rough_event(
    roughness: f64,
    (n1, n2): (f64, f64),
    dir: DVec2,
    normal: DVec2,
    stream: &mut Stream,
) -> (DVec2, bool) {
    let sigma = turn_spread(roughness);
    let arriving = -turn(sigma, normal, -dir, stream);
    let (left, reflected) = choose(n1, n2, arriving, normal, stream.uniform());
    (turn(sigma, normal, left, stream), reflected)
}

/// The density, per unit of the leaving direction's sine on its side, with
/// which rough glass of `roughness` sends light arriving along `dir` (from
/// index `n1` into `n2`, at an edge of unit normal `normal`) out along
/// `out`: reflected where `out` is on the side of arrival, refracted
/// otherwise. It integrates over the turned direction of arrival (a
/// midpoint rule of `steps` points): for the checks of [`interact`].
#[cfg(test)]
fn rough_density(
    roughness: f64,
    (n1, n2): (f64, f64),
    dir: DVec2,
    normal: DVec2,
    out: DVec2,
    steps: usize,
) -> f64 {
    let sigma = turn_spread(roughness);
    // The normal on the side of arrival, and the sines along its tangent.
    let n_a = if normal.dot(dir) > 0.0 {
        -normal
    } else {
        normal
    };
    let (s_in, _) = rough::sine_cosine(n_a, -dir);
    let reflected = n_a.dot(out) > 0.0;
    let n_out = if reflected { n_a } else { -n_a };
    let (s_out, _) = rough::sine_cosine(n_out, out);
    let mut sum = 0.0;
    for k in 0..steps {
        // The turned arrival's sine, on the side of arrival.
        let s = -1.0 + 2.0 * (k as f64 + 0.5) / steps as f64;
        let turned_in = rough::density(sigma, -s_in, s);
        if turned_in == 0.0 {
            continue;
        }
        let cos = (1.0 - s * s).max(0.0).sqrt();
        let f = crate::optics::fresnel(n1, n2, cos);
        // The smooth event's sine on the side it leaves by, along that
        // side's tangent: a reflection keeps the side and mirrors the
        // sine; a refraction keeps `n s` (Snell), and the other side's
        // tangent, that of the opposite normal, is the first's reversed.
        let (share, left) = if reflected {
            (f, -s)
        } else {
            let t = n1 / n2 * s;
            if t.abs() >= 1.0 {
                continue;
            }
            (1.0 - f, t)
        };
        sum += turned_in * share * rough::density(sigma, -left, s_out);
    }
    sum * 2.0 / steps as f64
}

/// The event at an edge of `body` (whose inside is on `inside`) reached
/// from side `arrival`; `normal` is the edge's unit normal (either
/// orientation). Reflection and refraction are chosen
/// with probabilities `F` and `1 - F`, so the power is unchanged on average
/// and exactly conserved at the edge.
#[allow(clippy::too_many_arguments)]
pub(crate) fn interact(
    scene: &Scene,
    body: u32,
    inside: Side,
    arrival: Side,
    dir: DVec2,
    normal: DVec2,
    state: &mut GlassState,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Event {
    stats.physics.glass_events += 1;
    let glass = scene.glass[body as usize];
    let mut colour = Rgb::ONE;
    let n = if glass.dispersion != 0.0 {
        let wavelength = match state.wavelength {
            Some(l) => l,
            None => {
                let (l, weight) = scene.spectra.draw(|| stream.uniform());
                state.wavelength = Some(l);
                colour = weight;
                l
            }
        };
        cauchy(glass.ior, glass.dispersion, wavelength)
    } else {
        glass.ior
    };
    let entering = arrival != inside;
    let (n1, n2) = if entering { (1.0, n) } else { (n, 1.0) };
    let (new_dir, reflected) = if glass.roughness > 0.0 {
        rough_event(glass.roughness, (n1, n2), dir, normal, stream)
    } else {
        choose(n1, n2, dir, normal, stream.uniform())
    };
    let now_inside = entering != reflected;
    state.inside = if now_inside { Some(body) } else { None };
    Event {
        dir: new_dir,
        colour,
        radiance_scale: if reflected { 1.0 } else { n1 / n2 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Rough glass's directions follow its density, on both sides, for
    /// light entering and leaving glass, near normal and grazing
    /// arrival, narrow and broad lobes: a chi-square over 24 bins of
    /// angle (23 degrees of freedom, the 0.1 % critical value 49.73).
    /// The density integrates to 1 over both sides: no light is lost.
    #[test]
    fn rough_glass_samples_its_density_and_keeps_every_photon() {
        let normal = DVec2::new(0.6, 0.8);
        let t = normal.perp();
        let mut stream = Stream::new(21, 22, 23);
        for (roughness, indices, arrival) in [
            (0.1, (1.0, 1.5), 0.4),
            (0.3, (1.5, 1.0), -0.5),
            (0.3, (1.0, 1.5), 1.3),
            (0.7, (1.5, 1.0), 0.2),
            (1.0, (1.0, 2.4), -1.0),
        ] {
            // Arriving from the normal's side, `arrival` radians off it.
            let dir = -(normal * f64::cos(arrival) + t * f64::sin(arrival));
            let bins = 24;
            let draws = 100_000;
            let mut counts = vec![0.0; bins];
            let bin_of = |w: DVec2| {
                let theta = t.dot(w).atan2(normal.dot(w));
                (((theta / (2.0 * PI) + 0.5) * bins as f64) as usize).min(bins - 1)
            };
            for _ in 0..draws {
                let (out, reflected) = rough_event(roughness, indices, dir, normal, &mut stream);
                assert!((out.length() - 1.0).abs() < 1e-12);
                assert_eq!(reflected, normal.dot(out) >= 0.0, "{out}");
                counts[bin_of(out)] += 1.0;
            }
            let (mut chi2, mut total) = (0.0, 0.0);
            for (b, &count) in counts.iter().enumerate() {
                let steps = 100;
                let p: f64 = (0..steps)
                    .map(|k| {
                        let theta = 2.0
                            * PI
                            * ((b as f64 + (k as f64 + 0.5) / steps as f64) / bins as f64 - 0.5);
                        let out = normal * theta.cos() + t * theta.sin();
                        // Per radian: the density per unit sine times |cos|.
                        rough_density(roughness, indices, dir, normal, out, 2000)
                            * theta.cos().abs()
                            * 2.0
                            * PI
                            / (bins * steps) as f64
                    })
                    .sum();
                total += p;
                let expected = p * draws as f64;
                chi2 += (count - expected) * (count - expected) / expected.max(1.0);
            }
            assert!(
                (total - 1.0).abs() < 2e-3,
                "{roughness} {indices:?}: {total}"
            );
            assert!(
                chi2 < 49.73,
                "{roughness} {indices:?} {arrival}: chi2 {chi2}"
            );
        }
    }

    /// The turned event is reciprocal: the density of leaving along `b`
    /// for light arriving along `-a`, divided by the index on `b`'s side,
    /// equals the density of leaving along `a` for light arriving along
    /// `-b`, divided by the index on `a`'s side (`L / n` is invariant in
    /// the plane), for reflections and refractions.
    #[test]
    fn rough_glass_is_reciprocal() {
        let normal = DVec2::new(0.0, 1.0);
        let at = |theta: f64, side: f64| DVec2::new(theta.sin(), side * theta.cos());
        for roughness in [0.2, 0.6] {
            for (a, b) in [(0.3, 0.9), (-0.4, 0.2), (1.2, -0.7)] {
                // Reflection on the glass side (index 1.5) and refraction
                // from air (1) into glass (1.5).
                let (wa, wb) = (at(a, 1.0), at(b, 1.0));
                let there = rough_density(roughness, (1.0, 1.5), -wa, normal, wb, 4000);
                let back = rough_density(roughness, (1.0, 1.5), -wb, normal, wa, 4000);
                assert!(
                    (there - back).abs() < 1e-6 * there.max(1.0),
                    "{there} {back}"
                );
                let (wa, wb) = (at(a, 1.0), at(b, -1.0));
                // Per unit sine the density of the sines times the index
                // is what is symmetric: d(n s) on each side.
                let there = rough_density(roughness, (1.0, 1.5), -wa, normal, wb, 4000) / 1.5;
                let back = rough_density(roughness, (1.5, 1.0), -wb, normal, wa, 4000) / 1.0;
                assert!(
                    (there - back).abs() < 1e-3 * there.max(1e-3),
                    "{roughness} {a} {b}: {there} {back}"
                );
            }
        }
    }
}
