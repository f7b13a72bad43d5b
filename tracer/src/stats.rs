//! Counts of what a render did, summed per tile in a fixed order.

use std::fmt;

/// What a render did, in two parts: the physics (samples, paths by how
/// they ended, scattering events, samples left out), which depends only
/// on the scene, the options and the estimator; and the work (rays cast,
/// walls tested, cache reads), which the fast paths change. Snapshots pin
/// the physics; the work shows what a fast path saved.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub physics: Physics,
    pub work: Work,
    /// The render's estimate of its own noise.
    pub noise: Noise,
    /// The first pass's noise, split between the floor's points and the
    /// rest of the samples (`passes::point_rate`).
    pub split: Split,
}

/// What happened to light: the same for the reference model and the fast
/// paths wherever the plan skips nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Physics {
    /// Receiver points drawn on the floor (one per pixel sample).
    pub camera_samples: u64,
    /// Photon paths emitted by the light tracer.
    pub light_paths: u64,
    /// Photons of the caustic pass: from points, spots and suns towards
    /// mirrors and glass.
    pub caustic_photons: u64,
    /// Caustic photons that ended at their first diffuse wall.
    pub paths_to_walls: u64,
    /// Paths whose last ray hit nothing.
    pub paths_escaped: u64,
    /// Paths stopped by a limit: the diffuse bounces, or the specular
    /// events in a row.
    pub paths_bounce_limit: u64,
    /// Paths ended by Russian roulette in a long run of specular events.
    pub paths_roulette: u64,
    /// Paths that read the rest of their light from the onward memo at a
    /// diffuse wall, and stopped there.
    pub paths_onward: u64,
    /// Paths whose throughput became exactly zero.
    pub paths_absorbed: u64,
    /// Reflections off mirrors.
    pub mirror_reflections: u64,
    /// Passes of a path through a transparent wall.
    pub transparent_passes: u64,
    /// Reflections and refractions at glass edges.
    pub glass_events: u64,
    /// Samples whose estimate was NaN or infinite, left out of the image.
    pub nonfinite_samples: u64,
    /// The first such sample taken, in tile order, then in the pixel's
    /// order of samples: (x, y, sample index).
    pub first_nonfinite: Option<(u32, u32, u32)>,
}

/// How the work was done: rays, culling, the caches.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Work {
    /// Visibility tests towards a light.
    pub shadow_rays: u64,
    /// Closest-hit rays of indirect paths (the first from the floor, then
    /// one after every reflection or pass through a transparent wall).
    pub bounce_rays: u64,
    /// Floor rays tested only against the walls of their arc of
    /// directions (a part of `bounce_rays`).
    pub culled_rays: u64,
    /// The walls those rays were tested against, in all.
    pub culled_walls_tested: u64,
    /// Culled floor rays whose arc meets no wall: their paths escape and
    /// add nothing, so they are neither traced nor in `bounce_rays`.
    pub culled_empty: u64,
    /// Rays off mirrors tested only against the walls of their mirror
    /// piece's arc of directions (a part of `bounce_rays`).
    pub culled_mirror_rays: u64,
    /// Shadow rays tested only against a list of the walls between their
    /// pixels and the light (a part of `shadow_rays`).
    pub listed_shadow_rays: u64,
    /// Shadow rays of the closed form for points, spots, suns and beams
    /// seen in a flat mirror, two legs a ray each (a part of
    /// `shadow_rays`).
    pub mirrored_shadow_rays: u64,
    /// Entries of the wall memo: (wall, side, bin, light) keys.
    pub memo_entries: u64,
    /// Bytes held by the wall memo.
    pub memo_bytes: u64,
    /// Shadow rays cast to fill the wall memo (not in `shadow_rays`).
    pub memo_fill_rays: u64,
    /// Wall-memo reads, each replacing one shadow ray per light.
    pub memo_lookups: u64,
    /// Wall-memo reads checked by next-event estimation (one in
    /// `flatray_cache::CHECK_RATE`), a part of `memo_lookups`.
    pub memo_checks: u64,
    /// Path samples that reused their pixel's memoised direct light.
    pub floor_memo_reuses: u64,
    /// Points of the floor memo (each pixel's, summed over its passes).
    pub floor_points: u64,
    /// Lines walked across the image for the floor's indirect light, and
    /// the pieces between walls they were cut into (`lines.rs`).
    pub lines: u64,
    pub line_pieces: u64,
    /// (pixel, light) pairs of the floor memo whose strata shared one
    /// visibility (one shadow ray, or none for a clear line light).
    pub floor_shared_visibility: u64,
    /// (pixel, light) pairs of the floor memo where a point, spot or sun
    /// looked at the walls in front of the pixel's square, to take its
    /// mean over the square in closed form (`estimators::square`).
    pub floor_square_lights: u64,
    /// Diffuse hits whose albedo was read from the floor.
    pub floor_albedo_reads: u64,
    /// Path rays tested against lights they can meet (after a mirror).
    pub emission_tests: u64,
    /// Lights chosen by the light table beside its always-lights (each a
    /// part of `shadow_rays`).
    pub chosen_lights: u64,
    /// Of those, lights that a wall hides from the point's whole cell:
    /// no shadow ray cast (`accel/dark.rs`).
    pub chosen_dark: u64,
    /// Bytes held by the light table, and the shadow rays its probes cast
    /// (not in `shadow_rays`).
    pub light_table_bytes: u64,
    pub light_table_rays: u64,
    /// Onward-memo reads, each replacing the rest of a path.
    pub onward_lookups: u64,
    /// Rays cast to fill the onward memo (not in `bounce_rays`), and the
    /// bytes it holds (a part of `memo_bytes`).
    pub onward_rays: u64,
    pub onward_bytes: u64,
    /// Gathers whose first ray tested only its wall piece's list
    /// (`accel/mirror.rs`).
    pub onward_listed_rays: u64,
}

/// A render's estimate of its own error, from the samples themselves: each
/// pixel's two halves of samples are two independent estimates of its
/// value, and their difference, scaled by the halves' sizes, estimates
/// the error of the whole. Summed over pixels in tile order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Noise {
    /// Pixels with an estimate (those of at least two samples).
    pub pixels: u64,
    /// Per channel, the sum over pixels of the estimated squared error.
    pub error_squared: [f64; 3],
    /// Per channel, the sum over pixels of the squared value.
    pub value_squared: [f64; 3],
    /// Over pixels and channels, the sum of the estimated squared error
    /// relative to the square of the pixel's value, floored as relMSE's
    /// reference value is (`metrics::relative_squared`).
    pub relative_squared: f64,
}

impl Noise {
    /// Adds a pixel whose halves differ by `difference` (in image units),
    /// of value `value`; `weight` is `n1 n2 / n^2` for halves of `n1` and
    /// `n2` of `n` samples (a quarter for equal halves).
    pub fn add(&mut self, difference: crate::Rgb, value: crate::Rgb, weight: f64) {
        if !(difference.is_finite() && value.is_finite()) {
            return;
        }
        self.pixels += 1;
        for c in 0..3 {
            let error_squared = difference[c] * difference[c] * weight;
            self.error_squared[c] += error_squared;
            self.value_squared[c] += value[c] * value[c];
            self.relative_squared += crate::metrics::relative_squared(error_squared, value[c]);
        }
    }

    pub fn merge(&mut self, other: &Noise) {
        self.pixels += other.pixels;
        for c in 0..3 {
            self.error_squared[c] += other.error_squared[c];
            self.value_squared[c] += other.value_squared[c];
        }
        self.relative_squared += other.relative_squared;
    }

    /// The estimated root relMSE (as `flatray converge` measures it
    /// against a reference: each pixel's error relative to its own value),
    /// if any pixel had an estimate and the image is not black.
    pub fn relmse(&self) -> Option<f64> {
        let value: f64 = self.value_squared.iter().sum();
        (self.pixels > 0 && value > 0.0)
            .then(|| (self.relative_squared / (3 * self.pixels) as f64).sqrt())
    }

    /// The estimated relative RMS error over every pixel and channel (as
    /// `flatray converge` measures it against a reference), if any pixel
    /// had an estimate and the image is not black.
    pub fn relative(&self) -> Option<f64> {
        let error: f64 = self.error_squared.iter().sum();
        let value: f64 = self.value_squared.iter().sum();
        (self.pixels > 0 && value > 0.0).then(|| (error / value).sqrt())
    }

    /// The same, per channel.
    pub fn relative_per_channel(&self) -> Option<[f64; 3]> {
        (self.pixels > 0).then(|| {
            std::array::from_fn(|c| {
                if self.value_squared[c] > 0.0 {
                    (self.error_squared[c] / self.value_squared[c]).sqrt()
                } else {
                    0.0
                }
            })
        })
    }
}

/// The first pass's noise at its probe pixels (`passes::is_probe`), split
/// in two independent parts: the floor memo's points and everything else
/// (the path samples and the caustic pass's photons). Each part's two
/// halves differ by `d`; `|d|^2 / (1/a + 1/b)`, for halves of `a` and `b`
/// points (or samples), is that part's squared error times its count, so
/// the two sums say how the error of each falls as its count grows.
/// Summed over the probes in tile order.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Split {
    /// Probe pixels measured.
    pub probes: u64,
    /// The floor points' squared error times their count, summed.
    pub points: f64,
    /// The rest's squared error times its samples, summed.
    pub paths: f64,
}

impl Split {
    /// Adds a probe whose points' halves of `points.1` and `points.2`
    /// points differ by `points.0`, and whose samples' halves of
    /// `paths.1` and `paths.2` differ by `paths.0`, each difference
    /// already in image units.
    pub(crate) fn add(&mut self, points: (crate::Rgb, u32, u32), paths: (crate::Rgb, u32, u32)) {
        let part = |(d, a, b): (crate::Rgb, u32, u32)| {
            let spread = 1.0 / a as f64 + 1.0 / b as f64;
            (a > 0 && b > 0).then(|| d.length_squared() / spread)
        };
        if let (Some(p), Some(q)) = (part(points), part(paths))
            && p.is_finite()
            && q.is_finite()
        {
            self.probes += 1;
            self.points += p;
            self.paths += q;
        }
    }

    pub fn merge(&mut self, other: &Split) {
        self.probes += other.probes;
        self.points += other.points;
        self.paths += other.paths;
    }
}

impl fmt::Display for Noise {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.relmse(), self.relative()) {
            (Some(m), Some(r)) => write!(
                f,
                "about {:.2} % relMSE, {:.2} % relative RMS error",
                m * 100.0,
                r * 100.0
            ),
            _ if self.pixels > 0 => write!(f, "none: the image is black"),
            _ => write!(f, "not estimated (it takes at least 2 samples per pixel)"),
        }
    }
}

impl Stats {
    pub(crate) fn record_nonfinite(&mut self, x: u32, y: u32, sample: u32) {
        let p = &mut self.physics;
        p.nonfinite_samples += 1;
        if p.first_nonfinite.is_none() {
            p.first_nonfinite = Some((x, y, sample));
        }
    }

    /// Adds `other`'s counts; keeps the earlier first non-finite sample.
    pub fn merge(&mut self, other: &Stats) {
        self.physics.merge(&other.physics);
        self.work.merge(&other.work);
        self.noise.merge(&other.noise);
        self.split.merge(&other.split);
    }

    /// All rays cast.
    pub fn rays(&self) -> u64 {
        self.work.shadow_rays + self.work.bounce_rays
    }

    /// The counts a user can act on: the physics, the rays cast, the
    /// cache's size and the noise. `Display` adds every work counter
    /// (culling, cache hits and reuses).
    pub fn summary(&self) -> impl fmt::Display + '_ {
        StatsText {
            stats: self,
            verbose: false,
        }
    }
}

impl Physics {
    /// Adds `other`'s counts; keeps the earlier first non-finite sample.
    pub fn merge(&mut self, other: &Physics) {
        self.camera_samples += other.camera_samples;
        self.light_paths += other.light_paths;
        self.caustic_photons += other.caustic_photons;
        self.paths_to_walls += other.paths_to_walls;
        self.paths_escaped += other.paths_escaped;
        self.paths_bounce_limit += other.paths_bounce_limit;
        self.paths_roulette += other.paths_roulette;
        self.paths_onward += other.paths_onward;
        self.paths_absorbed += other.paths_absorbed;
        self.mirror_reflections += other.mirror_reflections;
        self.transparent_passes += other.transparent_passes;
        self.glass_events += other.glass_events;
        self.nonfinite_samples += other.nonfinite_samples;
        if self.first_nonfinite.is_none() {
            self.first_nonfinite = other.first_nonfinite;
        }
    }
}

impl Work {
    pub fn merge(&mut self, other: &Work) {
        self.shadow_rays += other.shadow_rays;
        self.bounce_rays += other.bounce_rays;
        self.culled_rays += other.culled_rays;
        self.culled_walls_tested += other.culled_walls_tested;
        self.culled_empty += other.culled_empty;
        self.culled_mirror_rays += other.culled_mirror_rays;
        self.listed_shadow_rays += other.listed_shadow_rays;
        self.mirrored_shadow_rays += other.mirrored_shadow_rays;
        self.memo_entries += other.memo_entries;
        self.memo_bytes += other.memo_bytes;
        self.memo_fill_rays += other.memo_fill_rays;
        self.memo_lookups += other.memo_lookups;
        self.memo_checks += other.memo_checks;
        self.floor_memo_reuses += other.floor_memo_reuses;
        self.floor_points += other.floor_points;
        self.lines += other.lines;
        self.line_pieces += other.line_pieces;
        self.floor_shared_visibility += other.floor_shared_visibility;
        self.floor_square_lights += other.floor_square_lights;
        self.floor_albedo_reads += other.floor_albedo_reads;
        self.emission_tests += other.emission_tests;
        self.chosen_lights += other.chosen_lights;
        self.chosen_dark += other.chosen_dark;
        self.light_table_bytes += other.light_table_bytes;
        self.light_table_rays += other.light_table_rays;
        self.onward_lookups += other.onward_lookups;
        self.onward_rays += other.onward_rays;
        self.onward_listed_rays += other.onward_listed_rays;
        self.onward_bytes += other.onward_bytes;
    }
}

/// Every count, the work counters too.
impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        StatsText {
            stats: self,
            verbose: true,
        }
        .fmt(f)
    }
}

/// The physics alone: what snapshots pin.
impl fmt::Display for Physics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self;
        writeln!(f, "samples")?;
        writeln!(f, "  camera samples   {:>14}", p.camera_samples)?;
        writeln!(f, "  light paths      {:>14}", p.light_paths)?;
        if p.caustic_photons > 0 {
            writeln!(f, "  caustic photons  {:>14}", p.caustic_photons)?;
        }
        writeln!(f, "paths ended by")?;
        writeln!(f, "  escaping         {:>14}", p.paths_escaped)?;
        writeln!(f, "  bounce limit     {:>14}", p.paths_bounce_limit)?;
        writeln!(f, "  absorption       {:>14}", p.paths_absorbed)?;
        if p.paths_roulette > 0 {
            writeln!(f, "  roulette         {:>14}", p.paths_roulette)?;
        }
        if p.paths_to_walls > 0 {
            writeln!(f, "  at a diffuse wall {:>13}", p.paths_to_walls)?;
        }
        if p.paths_onward > 0 {
            writeln!(f, "  onward memo      {:>14}", p.paths_onward)?;
        }
        writeln!(f, "events")?;
        writeln!(f, "  mirror bounces   {:>14}", p.mirror_reflections)?;
        writeln!(f, "  transparent      {:>14}", p.transparent_passes)?;
        writeln!(f, "  glass            {:>14}", p.glass_events)?;
        write!(f, "non-finite samples {:>14}", p.nonfinite_samples)?;
        if let Some((x, y, k)) = p.first_nonfinite {
            write!(f, " (first: pixel ({x}, {y}), sample {k})")?;
        }
        Ok(())
    }
}

/// The counts as text; the work counters only when `verbose`.
struct StatsText<'a> {
    stats: &'a Stats,
    verbose: bool,
}

impl fmt::Display for StatsText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (s, verbose) = (self.stats, self.verbose);
        writeln!(f, "{}", s.physics)?;
        write_noise(f, &s.noise)?;
        let w = &s.work;
        writeln!(f, "work")?;
        writeln!(f, "  shadow rays      {:>14}", w.shadow_rays)?;
        writeln!(f, "  bounce rays      {:>14}", w.bounce_rays)?;
        if w.onward_rays > 0 {
            writeln!(f, "  onward fill rays {:>14}", w.onward_rays)?;
            if verbose {
                writeln!(f, "  onward listed    {:>14}", w.onward_listed_rays)?;
            }
        }
        if verbose {
            writeln!(f, "  culled rays      {:>14}", w.culled_rays)?;
            writeln!(f, "  walls tested     {:>14}", w.culled_walls_tested)?;
            writeln!(f, "  arc has no wall  {:>14}", w.culled_empty)?;
            writeln!(f, "  culled off mirrors {:>12}", w.culled_mirror_rays)?;
            writeln!(f, "  listed shadow rays {:>12}", w.listed_shadow_rays)?;
            writeln!(f, "  mirrored shadow rays {:>10}", w.mirrored_shadow_rays)?;
            writeln!(f, "  floor albedo     {:>14}", w.floor_albedo_reads)?;
            writeln!(f, "  emission tests   {:>14}", w.emission_tests)?;
            writeln!(f, "  wall entries     {:>14}", w.memo_entries)?;
        }
        write!(f, "  wall cache bytes {:>14}", w.memo_bytes)?;
        if verbose {
            writeln!(f)?;
            writeln!(f, "  wall fill rays   {:>14}", w.memo_fill_rays)?;
            writeln!(f, "  wall cache hits  {:>14}", w.memo_lookups)?;
            writeln!(f, "  wall cache checks{:>14}", w.memo_checks)?;
            writeln!(f, "  floor reuses     {:>14}", w.floor_memo_reuses)?;
            writeln!(f, "  floor points     {:>14}", w.floor_points)?;
            writeln!(f, "  floor lines      {:>14}", w.lines)?;
            writeln!(f, "  line pieces      {:>14}", w.line_pieces)?;
            writeln!(f, "  floor shared     {:>14}", w.floor_shared_visibility)?;
            writeln!(f, "  floor squares    {:>14}", w.floor_square_lights)?;
            writeln!(f, "  chosen lights    {:>14}", w.chosen_lights)?;
            writeln!(f, "  chosen dark      {:>14}", w.chosen_dark)?;
            writeln!(f, "  light table rays {:>14}", w.light_table_rays)?;
            writeln!(f, "  onward hits      {:>14}", w.onward_lookups)?;
            writeln!(f, "  onward bytes     {:>14}", w.onward_bytes)?;
            write!(f, "  light table bytes {:>13}", w.light_table_bytes)?;
        }
        Ok(())
    }
}

/// The noise estimate, overall and per channel.
fn write_noise(f: &mut fmt::Formatter<'_>, noise: &Noise) -> fmt::Result {
    writeln!(f, "noise (estimated from two halves of the samples)")?;
    match (
        noise.relative(),
        noise.relative_per_channel(),
        noise.relmse(),
    ) {
        (Some(all), Some([r, g, b]), Some(relmse)) => {
            writeln!(f, "  relMSE (root)    {:>13.3}%", relmse * 100.0)?;
            writeln!(f, "  relative RMS     {:>13.3}%", all * 100.0)?;
            writeln!(
                f,
                "  red, green, blue {:>5.3}%, {:.3}%, {:.3}%",
                r * 100.0,
                g * 100.0,
                b * 100.0
            )
        }
        _ => writeln!(f, "  not estimated (at least 2 samples per pixel)"),
    }
}
