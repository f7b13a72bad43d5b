//! Light tracing from the lights (the original project's proposed future
//! work): photon paths leave the lights, bounce through the scene, and
//! every free flight adds its exact track length in each pixel it crosses
//! to that pixel's fluence.

use flatray_geometry::{DVec2, Ray, Side, Skip, clip_to_box};

use crate::film::PixelSums;
use crate::film::{Estimator, Film, Part, run};
use crate::ledger::{self, Ledger};
use crate::lights::{Photon, PhotonKernel};
use crate::material::glass::{GlassState, absorption, transmit};
use crate::material::{Bsdf, Sampling, Transport};
use crate::options::{RenderOptions, image_size};
use crate::passes::Pass;
use crate::run::{Limits, Run};
use crate::sampling::Stream;
use crate::scene::{Light, Scene};
use crate::{Rgb, Stats};

/// The number of fixed work chunks: each sums its paths in order into its
/// own buffer, and the buffers are merged in chunk order, so the image is
/// the same for any number of threads.
const MAX_CHUNKS: usize = 16;
/// Bytes the chunk buffers may take together.
const CHUNK_BUDGET: usize = 256 << 20;

/// One pass of a light-traced render (`passes.rs`): the pass's samples
/// times the pixels in photon paths, from the pass's own seed; each
/// pixel's sums (all the paths for the whole, and apart the first half of
/// the chunks' paths, counted as that share of the pass's samples), and
/// that share of its samples.
pub(crate) fn light_pass(
    scene: &Scene,
    options: &RenderOptions,
    pass: &Pass,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<PixelSums>, Stats, f64) {
    let (width, height) = image_size(scene, options.scale);
    let pixels = width as usize * height as usize;
    // A photon at a black wall stops there: its power is zero.
    let limits = Limits::of(options);
    let paths = pass.count() as u64 * pixels as u64;

    let powers: Vec<f64> = scene
        .lights
        .iter()
        .map(|l| l.intensity * l.shape.power(scene))
        .collect();
    let total: f64 = powers.iter().sum();
    let mut cumulative = Vec::with_capacity(powers.len());
    let mut acc = 0.0;
    for p in &powers {
        acc += p / total.max(f64::MIN_POSITIVE);
        cumulative.push(acc);
    }
    if total <= 0.0 || paths == 0 {
        return (vec![PixelSums::default(); pixels], Stats::default(), 0.0);
    }
    // As many chunks as the budget holds (a light-traced path crosses many
    // pixels: tracing a chunk costs far more than clearing its buffer),
    // and two where the budget allows (the noise estimate's halves).
    let chunks = (CHUNK_BUDGET / (pixels.max(1) * 24)).clamp(1, MAX_CHUNKS);
    let estimator = Photons {
        scene,
        pass,
        size: (width, height),
        limits,
        paths,
        weight: total / paths as f64,
        cumulative,
        chunks,
        per_chunk: paths.div_ceil(chunks as u64),
        grid: Grid::new(scene, options.scale, width, height),
    };
    let first = pass.count() as f64 * estimator.first_share();
    let outcome = run(&estimator, Stats::default(), progress);
    (outcome.output, outcome.stats, first)
}

/// Light tracing as units of the render loop: fixed chunks of photon
/// paths, each summed in order into a buffer of the whole image.
struct Photons<'a> {
    scene: &'a Scene,
    pass: &'a Pass,
    size: (u32, u32),
    limits: Limits,
    /// Photon paths in all, and each one's share of the total power.
    paths: u64,
    weight: f64,
    /// The lights' cumulative shares of the power: a light is chosen in
    /// proportion to its power.
    cumulative: Vec<f64>,
    chunks: usize,
    per_chunk: u64,
    grid: Grid,
}

impl Estimator for Photons<'_> {
    type Output = Vec<PixelSums>;

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn units(&self) -> usize {
        self.chunks
    }

    fn render_unit(
        &self,
        chunk: usize,
        stats: &mut Stats,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Part {
        let scene = self.scene;
        let mut buffer = vec![Rgb::ZERO; self.size.0 as usize * self.size.1 as usize];
        let first = chunk as u64 * self.per_chunk;
        let last = ((chunk as u64 + 1) * self.per_chunk).min(self.paths);
        let mut done = 0u64;
        for index in first..last {
            let mut stream = Stream::new(self.pass.seed, index, 0);
            let u = stream.uniform();
            let pick = self
                .cumulative
                .iter()
                .position(|&c| u < c)
                .unwrap_or(self.cumulative.len() - 1);
            let light = &scene.lights[pick];
            trace_photon(
                scene,
                (pick, light),
                self.weight,
                self.limits,
                &self.grid,
                &mut buffer,
                &mut stream,
                stats,
            );
            done += 1;
            if done.is_multiple_of(4096) {
                progress(4096);
            }
        }
        progress(done % 4096);
        Part::Splats {
            fluence: buffer,
            walls: Vec::new(),
            first_half: chunk < self.chunks / 2,
        }
    }

    fn finish(&self, film: Film, _stats: &mut Stats) -> Vec<PixelSums> {
        // Every path counts for the whole; the first half of the chunks'
        // paths, apart, for the noise estimate.
        let (n, share) = (self.pass.count() as f64, self.first_share());
        (0..self.size.0 as usize * self.size.1 as usize)
            .map(|k| {
                let (first, _) = film.split(k, (self.paths, self.first_paths()));
                let whole = film.fluence.get(k).copied().unwrap_or(Rgb::ZERO);
                PixelSums {
                    all: whole * n,
                    first: first * (n * share),
                }
            })
            .collect()
    }
}

impl Photons<'_> {
    /// The paths of the first half of the chunks.
    fn first_paths(&self) -> u64 {
        ((self.chunks / 2) as u64 * self.per_chunk).min(self.paths)
    }

    /// Their share of the paths, where both halves have paths (else 0:
    /// no estimate of the noise).
    fn first_share(&self) -> f64 {
        let first = self.first_paths();
        match first > 0 && first < self.paths {
            true => first as f64 / self.paths as f64,
            false => 0.0,
        }
    }
}

/// Emits one photon from `light` and follows it, depositing into `buffer`.
#[allow(clippy::too_many_arguments)]
fn trace_photon(
    scene: &Scene,
    (index, light): (usize, &Light),
    weight: f64,
    limits: Limits,
    grid: &Grid,
    buffer: &mut [Rgb],
    stream: &mut Stream,
    stats: &mut Stats,
) {
    stats.physics.light_paths += 1;
    let mut photon = light.shape.emit(light, scene, stream);
    if let Some(wall) = scene.laser_wall(index) {
        photon.skip = Skip::one(wall);
    }
    let mut colour = light.color;
    if let Some((wavelength, of_it)) = scene.spectra.photon(index, || stream.uniform()) {
        photon.wavelength = Some(wavelength);
        colour = of_it;
    }
    let power = colour * weight * photon.scale;
    let mut deposits = Deposits {
        ledger: Ledger::default(),
        area: false,
        grid,
        floor: buffer,
        walls: None,
    };
    follow_photon(scene, photon, power, limits, &mut deposits, stream, stats);
}

/// Where a photon's light on a diffuse wall is kept, when it is kept:
/// the caustic pass's bins along the walls (`caustics::WallBins`).
pub(crate) trait WallDeposits: Sync {
    /// Adds `power`, arriving at the point `u` of wall `wall` from `side`,
    /// to `values`.
    fn add(&self, values: &mut [Rgb], at: (u32, flatray_geometry::Side, f64), power: Rgb);

    /// Adds `power` that took one glossy reflection on its way (off a
    /// rough mirror, after a mirror or glass): kept apart, as it counts
    /// one reflection more.
    fn add_late(&self, values: &mut [Rgb], at: (u32, flatray_geometry::Side, f64), power: Rgb);
}

/// Where a photon's light goes: the floor's pixels, and for the caustic
/// pass the diffuse walls' bins.
pub(crate) struct Deposits<'a> {
    pub grid: &'a Grid,
    pub floor: &'a mut [Rgb],
    /// The caustic pass (`caustics.rs`): a photon's flights count only
    /// after its first specular event (a mirror or glass), and it stops at
    /// its first diffuse wall, its power binned there, if it has been
    /// specular before.
    pub walls: Option<(&'a dyn WallDeposits, &'a mut [Rgb])>,
    /// In the caustic pass: which flights count and where a photon stops
    /// (`ledger.rs`).
    pub ledger: Ledger,
    /// Whether the photon comes from a line or circle light.
    pub area: bool,
}

/// Follows `photon`, of `power`, through at most `limits.bounces` diffuse
/// reflections and `limits.specular` specular events in a row
/// (`run.rs`), depositing each free flight's track length into the
/// floor's pixels it crosses.
pub(crate) fn follow_photon(
    scene: &Scene,
    photon: Photon,
    power: Rgb,
    limits: Limits,
    deposits: &mut Deposits,
    stream: &mut Stream,
    stats: &mut Stats,
) {
    let mut power = power;
    let r0 = scene.small_radius;
    let mut ray = Ray::new(photon.origin, photon.dir);
    let mut skip = photon.skip;
    // The first flight reproduces the kernel: the photon says how.
    let mut kernel = photon.kernel;
    // Distance along the first flight, unfolded through transparent walls
    // and mirrors: the kernel applies until the first diffuse reflection,
    // as for a mirror image of the light.
    let mut travelled = 0.0;
    let mut diffuse = 0;
    let mut run = Run::new(power);
    let caustic = deposits.walls.is_some();
    let ledger = deposits.ledger;
    // In the caustic pass: its history as the ledger reads it, which says
    // which of its flights count on the floor and where it stops.
    let mut history = ledger::Photon {
        area: deposits.area,
        // A laser's light no path finds: the caustic pass counts all of it.
        unseen: photon.unseen,
        ..ledger::Photon::default()
    };
    let mut glass = GlassState {
        inside: None,
        wavelength: photon.wavelength,
    };
    loop {
        stats.work.bounce_rays += 1;
        let hit = scene.segments.closest_hit(&ray, f64::INFINITY, skip);
        let t_end = hit.map_or(f64::INFINITY, |(_, h)| h.t);
        // The medium of this flight: known exactly when it ends at a glass
        // edge reached from inside, else the tracked state.
        let body = match hit {
            Some((index, h)) => {
                let wall = &scene.walls[index as usize];
                let arrival = wall
                    .shape
                    .arrival_side(ray.at(h.t), ray.dir)
                    .unwrap_or(Side::Positive);
                glass.flight_body(&wall.material, arrival)
            }
            None => glass.inside,
        };
        let absorb = absorption(scene, body);
        if !caustic || ledger.photon_lights_floor(&history) {
            deposits.grid.deposit(
                &ray,
                t_end,
                power,
                kernel,
                travelled,
                absorb,
                r0,
                deposits.floor,
                stream,
            );
        }
        let Some((index, h)) = hit else {
            stats.physics.paths_escaped += 1;
            return;
        };
        travelled += h.t;
        power *= transmit(absorb, h.t);
        if h.u == 0.0 || h.u == 1.0 {
            // The corner rule (see the path tracer).
            stats.physics.paths_absorbed += 1;
            return;
        }
        let wall = &scene.walls[index as usize];
        let x = wall.shape.point_at(h.u);
        let Some(side) = wall.shape.arrival_side(x, ray.dir) else {
            stats.physics.paths_escaped += 1;
            return;
        };
        let bsdf = Bsdf::at(scene, wall.material, (index, h.u, x), true, stats);
        if bsdf.is_straight() {
            stats.physics.transparent_passes += 1;
        }
        if let Some((bins, values)) = &mut deposits.walls
            && !bsdf.is_specular()
        {
            // The caustic pass ends at the first non-specular wall but
            // where the ledger says the photon goes on: one glossy
            // reflection (the path tracer leaves a point, spot or sun at
            // a path's first glossy vertex to it), and every reflection
            // of light that no path finds. What arrives at a diffuse wall
            // after specular events only is binned, for the path tracer's
            // next-event estimation to read; a glossy wall's outgoing
            // light depends on where light came from, which bins of
            // irradiance do not keep.
            let at = match bsdf.lambertian() {
                Some(_) => ledger::Vertex::Diffuse,
                None => ledger::Vertex::Glossy,
            };
            match ledger.photon_at(&history, at) {
                ledger::AtWall::Scatter => {
                    if at == ledger::Vertex::Glossy {
                        history = ledger.photon_glossy(history);
                    }
                }
                stop => {
                    stats.physics.paths_to_walls += 1;
                    if let ledger::AtWall::Bin { level } = stop {
                        let arriving = power * kernel.factor(travelled, r0);
                        match level {
                            0 => bins.add(values, (index, side, h.u), arriving),
                            _ => bins.add_late(values, (index, side, h.u), arriving),
                        }
                    }
                    return;
                }
            }
        }
        if !bsdf.is_specular() {
            if diffuse == limits.bounces {
                stats.physics.paths_bounce_limit += 1;
                return;
            }
            diffuse += 1;
        }
        if bsdf.is_mirror() {
            stats.physics.mirror_reflections += 1;
        }
        // Photons carry power, which refraction conserves.
        let scattered = bsdf.sample(
            scene,
            (ray.dir, wall.shape.normal_on(side, x), side),
            Sampling::Cosine,
            Transport::Power,
            &mut glass,
            stream,
            stats,
        );
        if bsdf.is_specular() {
            power *= scattered.weight;
            if !bsdf.is_straight() {
                let event = ledger::Event::of(wall, side, glass.inside.is_some());
                history.run = history.run.with(event);
                let Some(weight) = run.next(limits.specular, power, stream, stats) else {
                    return;
                };
                power *= weight;
            }
        } else {
            // Power arriving at the wall, with the kernel's share: the
            // kernel applies up to the first diffuse reflection.
            power *= kernel.factor(travelled, r0) * scattered.weight;
            kernel = PhotonKernel::None;
            run = Run::new(power);
            history.run = ledger::Run::EMPTY;
        }
        ray = Ray::new(x, scattered.dir);
        if power == Rgb::ZERO {
            stats.physics.paths_absorbed += 1;
            return;
        }
        skip = Skip::one(index);
    }
}

/// `∫ exp(-a τ) dτ` over `t..t + length`, per channel: `length` where a
/// channel does not absorb.
fn absorbed_length(a: Rgb, t: f64, length: f64) -> Rgb {
    let one = |a: f64| {
        if a == 0.0 {
            length
        } else {
            (-a * t).exp() * -(-a * length).exp_m1() / a
        }
    };
    Rgb::new(one(a.x), one(a.y), one(a.z))
}

/// The pixel grid over the canvas, in pixel units.
pub(crate) struct Grid {
    origin: DVec2,
    scale: DVec2,
    width: u32,
    height: u32,
    /// Fluence per unit of world track length: 1 / pixel area.
    per_length: f64,
}

impl Grid {
    pub(crate) fn new(scene: &Scene, _scale: f64, width: u32, height: u32) -> Grid {
        let scale = DVec2::new(
            width as f64 / scene.canvas.width as f64,
            height as f64 / scene.canvas.height as f64,
        );
        Grid {
            origin: scene.canvas.origin,
            scale,
            width,
            height,
            per_length: scale.x * scale.y,
        }
    }

    /// The pixel that holds world point `x`, clamped to the image.
    pub(crate) fn pixel_at(&self, x: DVec2) -> (u32, u32) {
        let at = (x - self.origin) * self.scale;
        let clamp = |v: f64, n: u32| (v.floor().max(0.0) as u32).min(n.saturating_sub(1));
        (clamp(at.x, self.width), clamp(at.y, self.height))
    }

    /// Adds `power * length / area` to every pixel that `ray` crosses for
    /// `0 <= t < t_end` (Amanatides-Woo), with the kernel factor (the
    /// light `offset + t` away) and the absorption (`exp(-absorb t)`)
    /// integrated exactly along each crossing; where both vary there, at
    /// one uniform point of it, drawn from `stream`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn deposit(
        &self,
        ray: &Ray,
        t_end: f64,
        power: Rgb,
        kernel: PhotonKernel,
        offset: f64,
        absorb: Rgb,
        r0: f64,
        buffer: &mut [Rgb],
        stream: &mut Stream,
    ) {
        let flat = kernel.is_flat_beyond_r0();
        let scaled = power * self.per_length;
        self.walk(ray, t_end, |pixel, t, t_exit| {
            let length = t_exit - t;
            let flat_here = flat && offset + t >= r0;
            let deposit = if absorb == Rgb::ZERO {
                // The kernel's exact integral along the crossing.
                let along = if flat_here {
                    length
                } else {
                    kernel.integral(offset + t, offset + t_exit, r0)
                };
                scaled * along
            } else if flat_here {
                // Beer-Lambert's exact integral along the crossing.
                scaled * absorbed_length(absorb, t, length)
            } else {
                // Both vary along the crossing: their product at one
                // uniform point of it, an unbiased estimate.
                let at = t + length * stream.uniform();
                scaled * (length * kernel.factor(offset + at, r0)) * transmit(absorb, at)
            };
            buffer[pixel] += deposit;
        });
    }

    /// Adds `power * length / area` to every pixel that `ray` crosses for
    /// `0 <= t < t_end`: [`Grid::deposit`] with no kernel and no
    /// absorption.
    #[inline]
    pub(crate) fn deposit_flat(&self, ray: &Ray, t_end: f64, power: Rgb, buffer: &mut [Rgb]) {
        let scaled = power * self.per_length;
        self.walk(ray, t_end, |pixel, t, t_exit| {
            buffer[pixel] += scaled * (t_exit - t);
        });
    }

    /// Calls `cross(pixel, t, t_exit)` for every pixel that `ray` crosses
    /// for `0 <= t < t_end`, in order, with the crossing's range of `t`
    /// (Amanatides-Woo; `t` in world units, crossings of no length left
    /// out).
    #[inline(always)]
    fn walk(&self, ray: &Ray, t_end: f64, mut cross: impl FnMut(usize, f64, f64)) {
        // In pixel coordinates: p(t) = o + t d, t still in world units.
        let o = (ray.origin - self.origin) * self.scale;
        let d = ray.dir * self.scale;
        let (w, h) = (self.width as f64, self.height as f64);
        // Clip t to the canvas rectangle.
        let Some((t0, t1)) = clip_to_box(o, d, 0.0, t_end, DVec2::ZERO, DVec2::new(w, h)) else {
            return;
        };
        if t0 >= t1 {
            return;
        }
        let start = o + d * t0;
        let mut ix = (start.x.floor() as i64).clamp(0, self.width as i64 - 1);
        let mut iy = (start.y.floor() as i64).clamp(0, self.height as i64 - 1);
        let step_x: i64 = if d.x > 0.0 { 1 } else { -1 };
        let step_y: i64 = if d.y > 0.0 { 1 } else { -1 };
        let next_boundary = |i: i64, s: i64| (if s > 0 { i + 1 } else { i }) as f64;
        let mut t_next_x = if d.x != 0.0 {
            (next_boundary(ix, step_x) - o.x) / d.x
        } else {
            f64::INFINITY
        };
        let mut t_next_y = if d.y != 0.0 {
            (next_boundary(iy, step_y) - o.y) / d.y
        } else {
            f64::INFINITY
        };
        let dt_x = if d.x != 0.0 {
            1.0 / d.x.abs()
        } else {
            f64::INFINITY
        };
        let dt_y = if d.y != 0.0 {
            1.0 / d.y.abs()
        } else {
            f64::INFINITY
        };
        let mut t = t0;
        while t < t1 {
            let t_exit = t_next_x.min(t_next_y).min(t1);
            if t_exit > t {
                cross((iy as usize) * self.width as usize + ix as usize, t, t_exit);
            }
            t = t_exit;
            if t >= t1 {
                break;
            }
            if t_next_x <= t_next_y {
                ix += step_x;
                t_next_x += dt_x;
                if ix < 0 || ix >= self.width as i64 {
                    break;
                }
            } else {
                iy += step_y;
                t_next_y += dt_y;
                if iy < 0 || iy >= self.height as i64 {
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Beer-Lambert's integral along a crossing, per channel.
    #[test]
    fn absorbed_length_is_the_integral_of_the_transmittance() {
        let a = Rgb::new(0.0, 0.3, 2.0);
        let (t, length) = (1.7, 0.4);
        let n = 100_000;
        let h = length / n as f64;
        let numeric = (0..n).fold(Rgb::ZERO, |sum, k| {
            sum + transmit(a, t + (k as f64 + 0.5) * h) * h
        });
        let exact = absorbed_length(a, t, length);
        assert!(
            (exact - numeric).abs().max_element() < 1e-9,
            "{exact} {numeric}"
        );
    }
}
