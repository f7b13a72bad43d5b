//! What a path or a photon does at a glass edge: Fresnel reflection or
//! Snell refraction, chosen with the Fresnel probability, with Cauchy
//! dispersion (a wavelength drawn at the first dispersive edge) and
//! Beer-Lambert absorption inside.

use flatray_geometry::{DVec2, Side};

use crate::optics::{VISIBLE, cauchy, choose, wavelength_rgb};
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
                let l = VISIBLE.0 + (VISIBLE.1 - VISIBLE.0) * stream.uniform();
                state.wavelength = Some(l);
                colour = wavelength_rgb(l);
                l
            }
        };
        cauchy(glass.ior, glass.dispersion, wavelength)
    } else {
        glass.ior
    };
    let entering = arrival != inside;
    let (n1, n2) = if entering { (1.0, n) } else { (n, 1.0) };
    let (new_dir, reflected) = choose(n1, n2, dir, normal, stream.uniform());
    let now_inside = entering != reflected;
    state.inside = if now_inside { Some(body) } else { None };
    Event {
        dir: new_dir,
        colour,
        radiance_scale: if reflected { 1.0 } else { n1 / n2 },
    }
}
