//! Path tracing from the pixel: the estimator of `model.md`, written as an
//! iterative loop so that no scene can grow the stack.

use std::f64::consts::TAU;
use std::ops::ControlFlow;

use flatray_cache::{Check, Key, WallMemo};
use flatray_geometry::{DVec2, Hit, Ray, Side, Skip};

use crate::caustics::Caustics;
use crate::direct::{
    direct_light, direct_light_every, direct_light_glossy, glossy_emission_weight,
};
use crate::estimators::Receiver;
use crate::estimators::choice::LightTable;
use crate::ledger::{self, Ledger};
use crate::material::glass::{GlassState, absorption, transmit};
use crate::material::{Bsdf, Sampling, Transport};
use crate::memo::Onward;
use crate::run::Run;
use crate::sampling::{Stream, arc_point};
use crate::scene::{Scene, Wall};
use crate::{Integrator, Rgb, Stats};

/// One sample of the fluence at floor point `p`, with at most `bounces`
/// diffuse reflections between a light and the floor, and at most
/// `specular` mirror and glass events in a row (`run.rs`).
///
/// With `floor_direct` false the floor's own direct light is left out (the
/// render loop has it from the memo). With a `memo`, next-event estimation
/// at a diffuse wall reads it instead of casting shadow rays.
///
/// The ray that leaves the floor takes the direction `fraction` of the
/// way through `arc` (of [`crate::sampling::ARCS`]); the caller draws the
/// arc and the fraction uniformly (`sampling::sample_arc`,
/// `pixel::arc_fraction`), so that the direction is uniform.
pub(crate) fn path_sample(
    trace: &Trace,
    p: DVec2,
    direction: (usize, f64),
    sample: u32,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let begun = path_begin(trace, p, direction, None, stream, stats);
    let Some(ray) = begun.ray else {
        return begun.fluence;
    };
    let hit = trace
        .scene
        .segments
        .closest_hit(&ray, f64::INFINITY, Skip::NONE);
    path_finish(trace, begun.fluence, ray, hit, None, sample, stream, stats)
}

/// A path sample up to its first ray: the floor's direct light (when the
/// sample includes it) and the ray that leaves the floor, where the plan
/// traces indirect light.
#[derive(Clone, Copy)]
pub(crate) struct Begun {
    pub fluence: Rgb,
    pub ray: Option<Ray>,
}

/// The first part of [`path_sample`]: draws from `stream` exactly what
/// `path_sample` draws before its first ray.
/// With `shadow_walls` (per light, the walls that shadow rays from `p`
/// can cross), the floor's shadow rays test only those. Inlined, so that
/// the pixel loop compiled with AVX2 takes it with AVX2 too.
#[inline(always)]
pub(crate) fn path_begin(
    trace: &Trace,
    p: DVec2,
    (arc, fraction): (usize, f64),
    shadow_walls: Option<&[Option<Vec<u32>>]>,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Begun {
    let fluence = if trace.floor_direct {
        let receiver = Receiver {
            shadow_walls,
            ..Receiver::FLOOR
        };
        direct_light(
            trace.scene,
            p,
            receiver,
            (trace.shadows, &trace.ledger),
            trace.light_table,
            stream,
            stats,
        )
    } else {
        Rgb::ZERO
    };
    // The floor sees the whole circle: a direction uniform in the sample's
    // arc, the arc itself uniform (stratified over a pixel's samples), so
    // the direction is uniform on the circle: weight 2pi.
    if !trace.indirect {
        return Begun { fluence, ray: None };
    }
    let dir = arc_point(arc, fraction);
    Begun {
        fluence,
        ray: Some(Ray::new(p, dir)),
    }
}

/// The rest of [`path_sample`], given the fluence and the ray that
/// `path_begin` returned, and where that ray meets the walls. Inlined, so
/// that the hit stays in registers rather than passing through memory.
///
/// With `line_walls` (the walls the first ray's whole line can meet, in
/// index order), the rays that continue it straight through transparent
/// walls test only those: they start on that line (to within rounding,
/// far inside the lists' margin), so the answers are the same. A ray off a
/// mirror likewise tests only its mirror piece's list for its direction
/// (`Trace::mirror_arcs`), as do those that continue it.
///
/// `sample` is the pixel sample's index: it picks which half of the
/// onward memo the path reads (`onward.rs`).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn path_finish(
    trace: &Trace,
    fluence: Rgb,
    ray: Ray,
    first_hit: Option<(u32, Hit)>,
    line_walls: Option<&[u32]>,
    sample: u32,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    if first_hit.is_none() && !trace.force {
        // Escaped at once, as the loop below would find, with nothing met
        // on the way (emission is looked for only after a mirror).
        stats.work.bounce_rays += 1;
        stats.physics.paths_escaped += 1;
        return fluence;
    }
    let leg = Leg {
        throughput: Rgb::splat(TAU),
        bounce: 0,
        skip: Skip::NONE,
    };
    let onward = trace.onward.map(|onward| onward.for_sample(sample));
    follow(
        trace,
        fluence,
        ray,
        Some(first_hit),
        line_walls,
        leg,
        onward,
        stream,
        stats,
    )
}

/// Where a path's loop takes over: the throughput so far (`2pi` from the
/// floor), the diffuse reflections counted so far, and the wall the ray
/// leaves (a run of specular events starts there).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Leg {
    pub throughput: Rgb,
    pub bounce: u32,
    pub skip: Skip,
}

/// The path loop from `ray` on: `first_hit`, where known, is where `ray`
/// meets the walls. With `onward` (the onward memo's tables of one half,
/// `onward[m - 1]` for `m` reflections left), the path ends at its first
/// diffuse wall that leaves it a reflection, reading there what the rest
/// of the path would bring on average.
///
/// Each turn of the loop follows one ray: the lights it meets on the way
/// and the wall it arrives at ([`PathState::arrive`]), the light that
/// wall's vertex gathers by next-event estimation
/// ([`PathState::gather`]), and the ray that leaves it
/// ([`PathState::leave`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn follow(
    trace: &Trace,
    fluence: Rgb,
    ray: Ray,
    first_hit: Option<Option<(u32, Hit)>>,
    line_walls: Option<&[u32]>,
    leg: Leg,
    onward: Option<&[WallMemo]>,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    // The key of the memo's checks: the one-bounce shortcut, which holds
    // the stream as the loop is entered, decides alike.
    let path = stream.key();
    let mut first_hit = first_hit;
    let mut state = PathState::new(trace, fluence, ray, line_walls, leg);
    loop {
        stats.work.bounce_rays += 1;
        let hit = match first_hit.take() {
            Some(hit) => hit,
            None => trace.scene.segments.closest_hit_within(
                &state.ray,
                f64::INFINITY,
                state.skip,
                state.line_walls,
            ),
        };
        let Some(at) = state.arrive(trace, hit, stats) else {
            break;
        };
        let bsdf = Bsdf::at(
            trace.scene,
            at.wall.material,
            (at.index, at.h.u, at.x),
            trace.tables,
            stats,
        );
        if state
            .gather(trace, &at, &bsdf, (path, onward), stream, stats)
            .is_break()
        {
            break;
        }
        if state.leave(trace, &at, &bsdf, stream, stats).is_break() {
            break;
        }
    }
    state.fluence
}

/// What the path loop carries from one ray to the next.
struct PathState<'a> {
    fluence: Rgb,
    ray: Ray,
    throughput: Rgb,
    /// The wall the ray leaves.
    skip: Skip,
    /// The diffuse reflections so far.
    diffuse: u32,
    /// The specular events since the floor or the last diffuse wall.
    run: Run,
    /// After the last diffuse reflection the model allows, the path goes
    /// on only to meet lights with an area after specular events (which
    /// no shadow ray finds); its next diffuse wall ends it.
    last_leg: bool,
    /// The specular events since the floor or the last non-specular
    /// vertex, and that vertex: the ledger says from them whether a light
    /// the ray meets counts (`Ledger::path_meets`).
    events: ledger::Run,
    from: ledger::Vertex,
    /// Where the ray left a glossy wall, and the density of its
    /// direction: light with an area that it meets is weighed against
    /// next-event estimation there (multiple importance sampling).
    glossy_from: Option<GlossyStart>,
    /// Distance travelled since the receiver or the last diffuse vertex:
    /// a light seen through mirrors is that far away.
    unfolded: f64,
    glass: GlassState,
    /// The walls the current ray's line can meet, while it is known.
    line_walls: Option<&'a [u32]>,
}

/// Where a ray of the path loop arrives: the wall, where along it and on
/// which side.
struct Arrival<'s> {
    index: u32,
    h: Hit,
    wall: &'s Wall,
    x: DVec2,
    side: Side,
}

impl Arrival<'_> {
    /// The wall's unit normal on the arrival side.
    #[inline(always)]
    fn normal(&self) -> DVec2 {
        self.wall.shape.normal_on(self.side, self.x)
    }
}

impl<'a> PathState<'a> {
    #[inline(always)]
    fn new(
        trace: &Trace,
        fluence: Rgb,
        ray: Ray,
        line_walls: Option<&'a [u32]>,
        leg: Leg,
    ) -> PathState<'a> {
        let Leg {
            throughput,
            skip,
            bounce: diffuse,
        } = leg;
        PathState {
            fluence,
            ray,
            throughput,
            skip,
            diffuse,
            run: Run::new(throughput),
            last_leg: diffuse >= trace.bounces,
            events: ledger::Run::EMPTY,
            from: match diffuse {
                0 => ledger::Vertex::Floor,
                _ => ledger::Vertex::Diffuse,
            },
            glossy_from: None,
            unfolded: 0.0,
            glass: GlassState::default(),
            line_walls,
        }
    }

    /// The ray's flight to `hit`: the line and circle lights it crosses
    /// and the light of the wall it meets, where the ledger counts them
    /// from the run since the last vertex, and the glass it flies through.
    /// `None` where the path ends: it escapes, meets a wall exactly
    /// tangent or exactly at an end.
    #[inline(always)]
    fn arrive<'s>(
        &mut self,
        trace: &Trace<'s>,
        hit: Option<(u32, Hit)>,
        stats: &mut Stats,
    ) -> Option<Arrival<'s>> {
        let scene = trace.scene;
        let hit_t = hit.map_or(f64::INFINITY, |(_, h)| h.t);
        let meets = trace.ledger.path_meets(self.events, self.from).counts();
        if trace.mirror_emission && (meets || (trace.force && !self.events.is_specular())) {
            stats.work.emission_tests += 1;
            let emitted = emission_crossed(
                scene,
                &self.ray,
                hit_t,
                self.unfolded,
                self.glossy_from,
                self.glass.wavelength,
            );
            if meets {
                self.fluence += self.throughput * emitted;
            }
        }
        let Some((index, h)) = hit else {
            stats.physics.paths_escaped += 1;
            return None;
        };
        let wall = &scene.walls[index as usize];
        let x = wall.shape.point_at(h.u);
        let Some(side) = wall.shape.arrival_side(x, self.ray.dir) else {
            // A crossing implies the ray is not parallel to a segment; a
            // ray exactly tangent to an arc, to the last bit, ends here.
            stats.physics.paths_escaped += 1;
            return None;
        };
        if h.u == 0.0 || h.u == 1.0 {
            // The corner rule: a path that meets a wall exactly at an end
            // ends there. Leaving from a corner point, no side test could
            // tell the room's inside from its outside.
            stats.physics.paths_absorbed += 1;
            return None;
        }
        self.unfolded += h.t;
        if !scene.glass.is_empty() {
            // Times exactly 1 in a scene without glass.
            self.throughput *= transmit(
                absorption(scene, self.glass.flight_body(&wall.material, side)),
                h.t,
            );
        }
        if meets && let Some(light) = scene.light_of_wall(index) {
            self.fluence += self.throughput
                * wall_emission(
                    scene,
                    (light, x),
                    side,
                    self.unfolded,
                    self.glossy_from,
                    self.glass.wavelength,
                );
        }
        Some(Arrival {
            index,
            h,
            wall,
            x,
            side,
        })
    }

    /// The light that the vertex `at` with `bsdf` gathers: next-event
    /// estimation at a diffuse or glossy wall, and the onward memo's rest
    /// of the path where it holds it. Breaks where the path ends there:
    /// the bounce limit, or the onward memo's read.
    #[inline(always)]
    fn gather(
        &mut self,
        trace: &Trace,
        at: &Arrival,
        bsdf: &Bsdf,
        (path, onward): (u64, Option<&[WallMemo]>),
        stream: &mut Stream,
        stats: &mut Stats,
    ) -> ControlFlow<()> {
        let bounces = trace.bounces;
        // A transparent wall is no scattering event: the path goes on
        // straight, and nothing is counted.
        if bsdf.is_straight() {
            stats.physics.transparent_passes += 1;
        } else if !bsdf.is_specular() {
            if self.last_leg {
                stats.physics.paths_bounce_limit += 1;
                return ControlFlow::Break(());
            }
            self.diffuse += 1;
        }
        let diffuse = self.diffuse;
        if let Some(rho) = bsdf.lambertian() {
            // Next-event estimation, at the one non-specular BSDF: f E,
            // with f = rho / 2 and 2pi already in the throughput. The memo
            // holds E on each side of a diffuse wall.
            let point = WallPoint {
                index: at.index,
                side: at.side,
                u: at.h.u,
                x: at.x,
                path,
            };
            let normal = || at.normal();
            let irradiance = wall_irradiance(trace, point, &normal, diffuse, stream, stats);
            self.fluence += lambertian_light(self.throughput, rho, irradiance);
            if diffuse == bounces {
                if !trace.last_leg_sides.is_some_and(|sides| {
                    sides.get(2 * at.index as usize + at.side.index()) == Some(&true)
                }) {
                    stats.physics.paths_bounce_limit += 1;
                    return ControlFlow::Break(());
                }
                self.last_leg = true;
            }
            // The rest of the path, on average over its directions from
            // this wall: the onward memo, where it holds that many
            // reflections left.
            if let Some(table) = onward.and_then(|tables| {
                bounces
                    .checked_sub(diffuse + 1)
                    .and_then(|m| tables.get(m as usize))
            }) {
                stats.work.onward_lookups += 1;
                stats.physics.paths_onward += 1;
                self.fluence +=
                    self.throughput * rho * memo_irradiance(table, at.index, at.side, at.h.u);
                return ControlFlow::Break(());
            }
        }
        if bsdf.is_glossy() {
            // Next-event estimation through the lobe, each light weighed
            // against the lobe's own sample below.
            let point = (at.index, at.x, at.normal());
            self.fluence += self.throughput
                * glossy_direct(trace, point, (bsdf, -self.ray.dir), diffuse, stream, stats);
            if diffuse == bounces {
                if !trace.mirror_emission {
                    stats.physics.paths_bounce_limit += 1;
                    return ControlFlow::Break(());
                }
                // The lobe's sample still looks for lights with an area,
                // and goes on by mirrors and glass; its next non-specular
                // wall ends it.
                self.last_leg = true;
            }
        }
        ControlFlow::Continue(())
    }

    /// The ray that leaves the vertex `at` by sampling `bsdf`, and what
    /// the loop carries on with it: the run of specular events and the
    /// walls its line can meet. Breaks where the path ends: absorbed, or
    /// past the run's most specular events.
    #[inline(always)]
    fn leave(
        &mut self,
        trace: &Trace<'a>,
        at: &Arrival,
        bsdf: &Bsdf,
        stream: &mut Stream,
        stats: &mut Stats,
    ) -> ControlFlow<()> {
        let (index, x) = (at.index, at.x);
        let straight = bsdf.is_straight();
        if bsdf.is_mirror() {
            stats.physics.mirror_reflections += 1;
        }
        let sampling = match trace.integrator {
            // The light tracer never calls this function.
            Integrator::Path | Integrator::Light => Sampling::Cosine,
            Integrator::Original => Sampling::Uniform,
        };
        let scattered = bsdf.sample(
            trace.scene,
            (self.ray.dir, at.normal(), at.side),
            sampling,
            Transport::Radiance,
            &mut self.glass,
            stream,
            stats,
        );
        self.throughput *= scattered.weight;
        if self.throughput == Rgb::ZERO {
            stats.physics.paths_absorbed += 1;
            return ControlFlow::Break(());
        }
        let left = Ray::new(x, scattered.dir);
        self.glossy_from = if bsdf.is_glossy() {
            Some(GlossyStart {
                x,
                wall: index,
                pdf: bsdf.pdf(at.normal(), -self.ray.dir, scattered.dir, sampling),
            })
        } else if straight {
            self.glossy_from
        } else {
            None
        };
        self.ray = left;
        self.skip = Skip::one(index);
        if straight {
            // Still on the first ray's line: its walls still hold.
            return ControlFlow::Continue(());
        }
        if bsdf.is_specular() {
            let Some(weight) = self
                .run
                .next(trace.specular, self.throughput, stream, stats)
            else {
                return ControlFlow::Break(());
            };
            self.throughput *= weight;
            // The path goes against the light: the event as light takes it.
            let event = ledger::Event::of(at.wall, at.side, self.glass.inside.is_some());
            self.events = self.events.with(event.reversed());
            self.line_walls = if bsdf.is_mirror() {
                trace
                    .mirror_arcs
                    .and_then(|arcs| arcs.walls(index, at.h.u, self.ray.dir))
            } else {
                None
            };
            if self.line_walls.is_some() {
                stats.work.culled_mirror_rays += 1;
            }
        } else {
            self.run = Run::new(self.throughput);
            self.events = ledger::Run::EMPTY;
            self.from = match bsdf.is_glossy() {
                true => ledger::Vertex::Glossy,
                false => ledger::Vertex::Diffuse,
            };
            self.unfolded = 0.0;
            self.line_walls = None;
        }
        ControlFlow::Continue(())
    }
}

/// The walls that a ray leaving wall `wall` (a mirror, or a diffuse wall
/// the onward memo gathers from) at `u` in direction `dir` can meet, in
/// index order, where a fast path knows them (`accel/mirror.rs`); the path loop
/// then tests only those. `None`: every wall.
pub(crate) trait MirrorWalls: Sync {
    fn walls(&self, wall: u32, u: f64, dir: DVec2) -> Option<&[u32]>;
}

/// What one path sample needs to know beyond its position: the scene and
/// the switches of the render plan.
#[derive(Clone, Copy)]
pub(crate) struct Trace<'a> {
    pub scene: &'a Scene,
    /// Most diffuse reflections.
    pub bounces: u32,
    /// Most specular events in a row (`run.rs`).
    pub specular: u32,
    /// Whether a ray leaves the floor: false where the plan finds no
    /// light that could come back along it.
    pub indirect: bool,
    pub integrator: Integrator,
    /// Whether the sample includes the floor's own direct light.
    pub floor_direct: bool,
    /// The wall memo, read instead of shadow rays at diffuse walls.
    pub memo: Option<&'a WallMemo>,
    /// Whether memo reads are checked by next-event estimation at the
    /// rates the memo gives (`flatray_cache::Check::Sampled`): for paths
    /// from the floor, not for the onward memo's gathers, whose tables
    /// every pixel shares (they take the exact estimate alone wherever a
    /// bin's rate is below the usual one).
    pub memo_checks: bool,
    /// Whether shadow rays are cast (otherwise every light is visible).
    pub shadows: bool,
    /// Whether path rays look for line lights after a mirror.
    pub mirror_emission: bool,
    /// Who counts which light path (`ledger.rs`): what path rays that
    /// meet a light add, and what a rough mirror leaves to photons.
    pub ledger: Ledger,
    /// Per wall side, whether a path goes on past its last diffuse bounce
    /// there, to meet such lights after mirrors or glass
    /// (`run::last_leg_sides`); `None`: it never does.
    pub last_leg_sides: Option<&'a [bool]>,
    /// The reference model: look for them after every bounce (adding
    /// nothing).
    pub force: bool,
    /// The caustic pass's light on the diffuse walls, added to next-event
    /// estimation there.
    pub caustics: Option<&'a Caustics>,
    /// Whether a diffuse wall that takes the floor's albedo reads it from
    /// the scene's table along the walls (the same values) rather than
    /// from the floor.
    pub tables: bool,
    /// The walls that rays leaving each mirror (and diffuse wall, for the
    /// onward memo's gathers) can meet, when the plan culls rays by
    /// direction (a fast path: `accel/mirror.rs`).
    pub mirror_arcs: Option<&'a dyn MirrorWalls>,
    /// The lights each receiver's next-event estimation takes, where the
    /// plan chooses them (`estimators::choice`); `None`: every light.
    pub light_table: Option<&'a LightTable>,
    /// The onward memo: what the rest of a path brings from a diffuse
    /// wall, read instead of following it (`onward.rs`).
    pub onward: Option<Onward<'a>>,
}

/// The memo's irradiance on side `side` of wall `index` at `u`.
#[inline(always)]
pub(crate) fn memo_irradiance(memo: &WallMemo, index: u32, side: Side, u: f64) -> Rgb {
    let v = memo.lookup(Key {
        wall: index,
        side: side.index(),
        u,
    });
    Rgb::new(v[0] as f64, v[1] as f64, v[2] as f64)
}

/// [`memo_irradiance`], and how a path keyed `path` (the key of its
/// stream where it entered the loop, `Stream::key`) checks it; without
/// `sampled_checks`, only the reads always checked
/// (`WallMemo::read_unsampled`).
#[inline(always)]
pub(crate) fn memo_read(
    memo: &WallMemo,
    (index, side, u): (u32, Side, f64),
    path: u64,
    sampled_checks: bool,
) -> (Rgb, Check) {
    let key = Key {
        wall: index,
        side: side.index(),
        u,
    };
    let (v, check) = if sampled_checks {
        memo.read(key, path)
    } else {
        memo.read_unsampled(key)
    };
    (Rgb::new(v[0] as f64, v[1] as f64, v[2] as f64), check)
}

/// What the lights that are not walls emit towards `ray` where it meets
/// them before `t_max`, seen from `unfolded` further back: per radian,
/// `I G(r') r'` at the total distance `r` (`Falloff::per_radian`). For a
/// ray that left a glossy wall (`glossy_from`), each light's share
/// against next-event estimation there.
fn emission_crossed(
    scene: &Scene,
    ray: &Ray,
    t_max: f64,
    unfolded: f64,
    glossy_from: Option<GlossyStart>,
    wavelength: Option<f64>,
) -> Rgb {
    let mut sum = Rgb::ZERO;
    for (index, light) in scene.lights.iter().enumerate() {
        if let Some(t) = light.shape.met_by(ray, t_max) {
            let r = unfolded + t;
            // The ray runs from the receiver to the light: its light
            // arrives from `ray.dir`.
            let v = light.intensity
                * light.falloff.per_radian(r, scene.small_radius)
                * light.profile_at(ray.dir);
            let v = match glossy_from {
                Some(from) => {
                    v * glossy_emission_weight(
                        scene,
                        light,
                        (from.x, from.wall),
                        from.pdf,
                        ray.at(t),
                    )
                }
                None => v,
            };
            sum += scene.light_colour(index, wavelength) * v;
        }
    }
    sum
}

/// A point where a path meets a wall: the wall, the side it arrived on,
/// the position along it and the point; and the path's key, its stream's
/// where it entered the loop (the memo's checks, `memo_read`).
#[derive(Clone, Copy, Debug)]
struct WallPoint {
    index: u32,
    side: Side,
    u: f64,
    x: DVec2,
    path: u64,
}

/// The irradiance that next-event estimation gives a path at diffuse wall
/// point `at` (unit normal on its side from `normal`), after `diffuse`
/// reflections: the wall memo's read (checked by shadow rays as the memo
/// says, `flatray_cache::Check`), or shadow rays, and the caustic pass's bins.
#[inline(always)]
fn wall_irradiance(
    trace: &Trace,
    at: WallPoint,
    normal: &impl Fn() -> DVec2,
    diffuse: u32,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let Trace {
        scene,
        memo,
        shadows,
        light_table,
        ..
    } = *trace;
    let WallPoint {
        index, side, u, x, ..
    } = at;
    let receiver = || Receiver {
        normal: Some(normal()),
        wall: Some(index),
        shadow_walls: None,
    };
    let shadows = (shadows, &trace.ledger);
    let direct = |stream: &mut Stream, stats: &mut Stats| {
        direct_light(scene, x, receiver(), shadows, light_table, stream, stats)
    };
    // A check's estimate from every light the table does not prove dark:
    // no light's random choice leaves it below what arrives, so that the
    // check stays at or above zero where the memo says it would.
    let every = |stream: &mut Stream, stats: &mut Stats| {
        direct_light_every(scene, x, receiver(), shadows, light_table, stream, stats)
    };
    let irradiance = match memo {
        Some(memo) => {
            stats.work.memo_lookups += 1;
            let (read, check) = memo_read(memo, (index, side, u), at.path, trace.memo_checks);
            match check {
                Check::Sampled { rate } => {
                    // The memo's error, estimated where a hash of the hit
                    // picks it: unbiased, so the memo's bias (its bins hold
                    // the irradiance at their centres only) falls out.
                    stats.work.memo_checks += 1;
                    let direct = every(stream, stats);
                    read + (direct - read) * rate as f64
                }
                Check::Always => {
                    // Where the bins may be off by more than a sampled
                    // check takes out without going below zero.
                    stats.work.memo_checks += 1;
                    direct(stream, stats)
                }
                _ => read,
            }
        }
        None => direct(stream, stats),
    };
    add_caustics(trace, irradiance, (index, side, u), diffuse)
}

/// `irradiance` at a diffuse wall point, with what the caustic pass
/// binned there: all of it that a path can take after `diffuse`
/// reflections (light that took a glossy reflection on its way counts one
/// more, `Caustics::wall_late`).
#[inline(always)]
pub(crate) fn add_caustics(
    trace: &Trace,
    mut irradiance: Rgb,
    (index, side, u): (u32, Side, f64),
    diffuse: u32,
) -> Rgb {
    if let Some(caustics) = trace.caustics {
        irradiance += caustics.wall(index, side, u);
        if caustics.has_late() && trace.ledger.reads_bins(1, diffuse) {
            irradiance += caustics.wall_late(index, side, u);
        }
    }
    irradiance
}

/// What a Lambertian wall of albedo `rho` under `irradiance` sends along
/// a path of `throughput`: `f E` with `f = rho / 2` (the path's `2 pi`
/// from the floor already in the throughput).
#[inline(always)]
pub(crate) fn lambertian_light(throughput: Rgb, rho: Rgb, irradiance: Rgb) -> Rgb {
    throughput * rho * 0.5 * irradiance
}

/// The light a glossy wall point sends towards `wo` by next-event
/// estimation through its BSDF (`direct::direct_light_glossy`), at wall
/// `index`, point `x`, unit normal `n` on the path's side. At a path's
/// first non-specular vertex the caustic pass brings the light of points,
/// spots and suns off the lobe, and they are left out here.
#[inline(always)]
fn glossy_direct(
    trace: &Trace,
    (index, x, n): (u32, DVec2, DVec2),
    (bsdf, wo): (&Bsdf, DVec2),
    diffuse: u32,
    stream: &mut Stream,
    stats: &mut Stats,
) -> Rgb {
    let receiver = Receiver {
        normal: Some(n),
        wall: Some(index),
        shadow_walls: None,
    };
    let aimed_by_photons = trace.ledger.glossy_leaves_aimed(diffuse);
    direct_light_glossy(
        trace.scene,
        x,
        (receiver, n),
        (bsdf, wo),
        (trace.shadows, aimed_by_photons),
        stream,
        stats,
    )
}

/// What a path ray meeting line light `light`'s wall from `side` at
/// total distance `r` adds, per unit throughput: all of it after a
/// mirror, its share against next-event estimation after a glossy wall.
#[inline]
fn wall_emission(
    scene: &Scene,
    (light, at): (u32, DVec2),
    side: Side,
    r: f64,
    glossy_from: Option<GlossyStart>,
    wavelength: Option<f64>,
) -> Rgb {
    let colour = scene.light_colour(light as usize, wavelength);
    let light = &scene.lights[light as usize];
    let emitted = colour
        * light
            .shape
            .emitted_at_wall(light, side, r, scene.small_radius);
    match glossy_from {
        Some(from) => {
            emitted * glossy_emission_weight(scene, light, (from.x, from.wall), from.pdf, at)
        }
        None => emitted,
    }
}

/// Where a path's ray left a glossy wall: the point, the wall, and the
/// density per radian of the ray's direction.
#[derive(Clone, Copy, Debug)]
struct GlossyStart {
    x: DVec2,
    wall: u32,
    pdf: f64,
}
