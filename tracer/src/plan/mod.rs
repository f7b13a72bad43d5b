//! The render plan: what a scene holds (its [`Inventory`]) and what a
//! render of it does with that (the decisions). The integrators read the
//! decisions, so a skipped effect costs no rays; `Stats` counts prove it.
//! What the plan says to a user, effect by effect, is written apart
//! (`wording.rs`).

mod wording;

use crate::accel::Facts;
pub use crate::accel::{Decision, FastDecisions};
pub use crate::estimators::ClosedForms;
use crate::lights::LightCounts;
use crate::options::{FastPaths, Integrator, LightChoice, MANY_LIGHTS, RenderOptions};
use crate::scene::{Material, Scene};
use crate::{Floor, Rgb};

pub use wording::Effect;

/// What a scene holds, counted once: the facts every decision reads.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Inventory {
    pub points: usize,
    pub spots: usize,
    pub lines: usize,
    pub circles: usize,
    pub suns: usize,
    pub beams: usize,
    pub lasers: usize,
    /// Lights of one direction per point (points, spots, suns, beams,
    /// lasers), whose photons the caustic pass aims at mirrors and glass.
    pub aimed: usize,
    /// Lights a path ray can meet (lines and circles): path tracing sees
    /// them in mirrors.
    pub areas: usize,
    pub lights: usize,
    pub walls: usize,
    /// Walls that are circular arcs.
    pub arcs: usize,
    pub mirrors: usize,
    /// Rough mirrors: glossy walls, each a non-specular bounce.
    pub rough_mirrors: usize,
    pub panes: usize,
    pub glass_edges: usize,
    pub glass_bodies: usize,
    pub dispersive: usize,
    /// Glass bodies whose edges spread light (`roughness` above 0).
    pub rough_glass: usize,
    /// Lights with a spectrum.
    pub spectral: usize,
    pub diffuse: usize,
    /// Diffuse walls that take the floor's albedo.
    pub floor_albedo_walls: usize,
    /// Walls that can block light: all but clear panes.
    pub occluders: usize,
    /// Walls that send light on: not black, not panes.
    pub reflectors: usize,
    /// Mirrors and glass edges that send light on: mirrors not black.
    pub specular_reflectors: usize,
    /// How the walls' ray queries run, in words.
    pub queries: String,
}

impl Inventory {
    pub fn of(scene: &Scene) -> Inventory {
        let counts = LightCounts::of(&scene.lights);
        let walls =
            |f: &dyn Fn(&Material) -> bool| scene.walls.iter().filter(|w| f(&w.material)).count();
        let floor_black = matches!(scene.floor, Floor::Color(c) if c == Rgb::ZERO);
        Inventory {
            points: counts.points,
            spots: counts.spots,
            lines: counts.lines,
            circles: counts.circles,
            suns: counts.suns,
            beams: counts.beams,
            lasers: counts.lasers,
            aimed: counts.aimed,
            areas: scene.lights.iter().filter(|l| l.shape.has_area()).count(),
            lights: scene.lights.len(),
            walls: scene.walls.len(),
            arcs: scene
                .walls
                .iter()
                .filter(|w| w.shape.as_arc().is_some())
                .count(),
            mirrors: walls(&Material::is_mirror),
            rough_mirrors: walls(&Material::is_glossy),
            panes: walls(&Material::is_pane),
            glass_edges: walls(&Material::is_glass),
            glass_bodies: scene.glass.len(),
            dispersive: scene.glass.iter().filter(|g| g.dispersion != 0.0).count(),
            rough_glass: scene.glass.iter().filter(|g| g.roughness > 0.0).count(),
            spectral: scene.lights.iter().filter(|l| l.spectrum.is_some()).count(),
            diffuse: walls(&Material::is_diffuse),
            floor_albedo_walls: walls(&Material::takes_floor_albedo),
            occluders: walls(&Material::occludes),
            reflectors: walls(&|m| m.reflects(floor_black)),
            specular_reflectors: walls(&Material::reflects_specularly),
            queries: scene.segments().describe(),
        }
    }
}

/// What a render of a scene does: the inventory, the settings that the
/// decisions read, and the decisions.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    pub inventory: Inventory,
    /// The settings, as the decisions read them.
    pub bounces: u32,
    pub specular: u32,
    pub tracing_light: bool,
    pub reference: bool,
    pub memo_enabled: bool,
    pub caustics_enabled: bool,
    /// The wall memo's bin length, in pixels, as given.
    pub bin_length: String,
    /// The floor memo's points per pixel in the first pass.
    pub floor_points: u32,
    /// Whether the wall memo fits its budget.
    pub wall_memo_fits: bool,
    /// Wall-light pairs and pixel-light cells: what the coherence masks
    /// would cost.
    pub pairs: usize,
    pub mask_cells: u64,
    /// Shadow rays towards lights (otherwise every light is visible).
    pub shadows: bool,
    /// Indirect paths from the floor.
    pub indirect: bool,
    /// Lights with an area met by a path ray after a mirror or glass, or
    /// off a rough mirror.
    pub mirror_emission: bool,
    /// The closed forms through mirrors and glass, each with its reason
    /// (`estimators::ClosedForms`).
    pub closed_forms: ClosedForms,
    /// Line and circle lights send caustic photons at the mirror and
    /// glass edges, which take their light after runs of specular events
    /// that no closed form takes; path rays then add no light they meet
    /// after a run of specular events from the floor or a diffuse wall
    /// (`lights::aimed`).
    pub area_photons: bool,
    /// The segments those photons are aimed at.
    pub area_targets: usize,
    /// Paths go on past their last diffuse bounce, to meet lights with an
    /// area after mirrors and glass.
    pub last_legs: bool,
    /// The caustic pass: light from points, spots and suns through
    /// mirrors and glass, traced from the lights (`caustics.rs`).
    pub caustics: bool,
    /// The closed forms count every path of points, spots, suns and
    /// beams through mirrors and glass, so the caustic pass need not
    /// (`ClosedForms::take_aimed_runs`).
    pub aimed_runs_closed: bool,
    /// The wall half of the memo.
    pub wall_memo: bool,
    /// The onward memo: the rest of a path, read at its first diffuse
    /// wall (`onward.rs`).
    pub onward: bool,
    /// Whether the integrator is the original project's.
    pub original: bool,
    /// Whether the render options allow the onward memo.
    pub onward_enabled: bool,
    /// The floor half of the memo: direct light once per pixel.
    pub floor_memo: bool,
    /// The floor memo's strata share one shadow ray per light where no
    /// shadow edge crosses their pixel (`accel/coherence.rs`).
    pub floor_coherence: bool,
    /// Points, spots and suns give each pixel of the floor memo their
    /// mean over its square in closed form (`estimators::square`), not their
    /// points' shadow rays: the floor memo without a light table.
    pub floor_squares: bool,
    /// The floor's rays test only the walls that rays from their block of
    /// pixels, in their arc of directions, can meet (`ArcCandidates`).
    pub floor_ray_culling: bool,
    /// The floor's indirect light is gathered along lines across the
    /// image (`lines.rs`), not by each pixel's path samples: with the
    /// floor memo, which takes the floor's direct light, where no glass
    /// absorbs (a piece of line inside it would not see one radiance) and
    /// passes are not adaptive (lines cross every pixel).
    pub floor_lines: bool,
    /// Whether the render options allow lines (`--indirect lines`, the
    /// default), and whether its passes are adaptive.
    pub lines_enabled: bool,
    pub adaptive: bool,
    /// Glass bodies that absorb.
    pub absorbing_glass: usize,
    /// How long the pieces of a line between walls would be, on average,
    /// in tenths of a pixel (`lines::pieces_per_pixel`), and whether that
    /// is too short for lines to pay.
    pub line_piece_tenths: u32,
    pub dense_walls: bool,
    /// The fast paths the settings allow (`reference` aside).
    pub fast_paths: FastPaths,
    /// Where each fast path runs, and why, as it declares.
    pub fast: FastDecisions,
    /// The light choice as given.
    pub light_choice: LightChoice,
    /// Next-event estimation takes the lights a table of cells chooses
    /// (`estimators::choice`), not every light.
    pub light_table: bool,
}

impl Plan {
    /// Who counts which light path in this render (`ledger.rs`), from the
    /// plan's decisions.
    pub(crate) fn ledger(&self) -> crate::ledger::Ledger {
        crate::ledger::Ledger {
            mirror_lights: self.closed_forms.mirror_lights.runs,
            glass_lights: self.closed_forms.glass_lights.runs,
            aimed_mirrors: self.closed_forms.aimed_mirrors.runs,
            area_photons: self.area_photons,
            caustics: self.caustics,
            bounces: self.bounces,
        }
    }

    /// The plan for `scene` rendered with `options`. With
    /// `options.reference`, every effect is on wherever it cannot change
    /// the image, and no fast path runs.
    pub fn new(scene: &Scene, options: &RenderOptions) -> Plan {
        let inventory = Inventory::of(scene);
        let Inventory {
            diffuse,
            reflectors,
            glass_edges,
            ..
        } = inventory;
        let force = options.reference;
        // The light tracer casts no shadow ray and reads no memo.
        let tracing_light = options.integrator == Integrator::Light;
        let shadows =
            !tracing_light && (force || (inventory.occluders > 0 && !scene.lights.is_empty()));
        let closed_forms = ClosedForms::of(scene, options, shadows);
        let aimed_runs_closed = closed_forms.take_aimed_runs(scene);
        let transport = transport_decisions(scene, options, &inventory, aimed_runs_closed);
        let (wall_memo_fits, wall_memo, onward) = memo_decisions(
            scene,
            options,
            MemoFacts {
                tracing_light,
                indirect: transport.indirect,
                force,
                diffuse,
                reflectors,
                glass_edges,
            },
        );
        let floor = floor_decisions(scene, options, &inventory, &transport);
        let pairs = scene.walls.len() * scene.lights.len();
        let (width, height) = crate::options::image_size(scene, options.scale);
        let mask_cells = width as u64 * height as u64 * scene.lights.len() as u64;
        // Each fast path says where it runs (`accel`). With a light table
        // too, a pixel's points trace a shared transmittance once, when
        // one of them first takes that light.
        let fast = FastDecisions::of(&Facts {
            options,
            walls: scene.walls.len(),
            arcs: inventory.arcs,
            lights: scene.lights.len(),
            mirrors: inventory.mirrors,
            floor_albedo_walls: inventory.floor_albedo_walls,
            tracing_light,
            indirect: transport.indirect,
            shadows,
            floor_memo: floor.floor_memo,
            wall_memo,
            onward,
            light_table: floor.light_table,
            pairs,
            mask_cells,
        });
        Plan {
            floor_coherence: fast.coherence.runs,
            floor_ray_culling: fast.culling.runs,
            fast,
            fast_paths: options.fast_paths,
            light_choice: options.light_choice,
            light_table: floor.light_table,
            inventory,
            bounces: options.bounces,
            specular: options.specular,
            tracing_light,
            reference: options.reference,
            memo_enabled: options.memo.enabled,
            caustics_enabled: options.caustics,
            bin_length: options.memo.bin_length.to_string(),
            floor_points: crate::passes::pass_points(
                options.samples.min(crate::passes::FIRST_PASS),
                options.memo.floor_samples,
                crate::passes::PointRule::First {
                    light_table: floor.light_table,
                },
            ),
            wall_memo_fits,
            pairs,
            mask_cells,
            shadows,
            indirect: transport.indirect,
            mirror_emission: transport.mirror_emission,
            closed_forms,
            area_photons: transport.area_photons,
            area_targets: transport.area_targets,
            last_legs: transport.last_legs,
            caustics: transport.caustics,
            aimed_runs_closed,
            wall_memo,
            onward,
            original: options.integrator == Integrator::Original,
            onward_enabled: options.memo.onward,
            floor_memo: floor.floor_memo,
            floor_squares: floor.floor_squares,
            floor_lines: floor.floor_lines,
            lines_enabled: options.floor_lines,
            adaptive: options.adaptive,
            absorbing_glass: floor.absorbing_glass,
            line_piece_tenths: floor.line_piece_tenths,
            dense_walls: floor.dense_walls,
        }
    }
}

/// How light gets from the lights to the floor in a render: whether
/// paths leave the floor, which lights path rays meet, and what the
/// caustic pass takes ([`transport_decisions`]).
struct Transport {
    /// Paths can bring light back at all: bounces, or mirrors and glass.
    indirect_possible: bool,
    indirect: bool,
    mirror_emission: bool,
    area_targets: usize,
    area_photons: bool,
    last_legs: bool,
    caustics: bool,
}

/// The plan's decisions of how light travels (`Plan::indirect`,
/// `mirror_emission`, `area_photons`, `last_legs`, `caustics`).
/// `aimed_runs_closed` says the closed forms count all light of points,
/// spots, suns and beams after mirrors and glass
/// (`ClosedForms::take_aimed_runs`).
fn transport_decisions(
    scene: &Scene,
    options: &RenderOptions,
    inventory: &Inventory,
    aimed_runs_closed: bool,
) -> Transport {
    let Inventory {
        aimed,
        lasers,
        areas,
        rough_mirrors,
        glass_edges,
        reflectors,
        specular_reflectors,
        ..
    } = *inventory;
    let force = options.reference;
    let no_lights = scene.lights.is_empty();
    let tracing_light = options.integrator == Integrator::Light;
    // Light can come by mirrors and glass without a diffuse bounce.
    let specular_paths = options.specular > 0 && specular_reflectors > 0;
    let indirect_possible = (options.bounces > 0 || specular_paths) && !no_lights;
    // Rays leave the floor where they can bring light back: off a
    // wall that reflects, within the bounces, or from a light with an
    // area seen in a mirror or through glass.
    let indirect = indirect_possible
        && ((options.bounces > 0 && (force || reflectors > 0)) || (specular_paths && areas > 0));
    // A rough mirror's own samples meet lights with an area, weighed
    // against next-event estimation there.
    let glossy_paths = options.bounces > 0 && rough_mirrors > 0;
    let mirror_emission = indirect && (force || ((specular_paths || glossy_paths) && areas > 0));
    // Lines and circles through glass: what enters a body and leaves
    // it, or reflects inside it first, photons take far better than
    // paths, which meet a small light by chance. Not with arc lights,
    // which paths find as walls.
    let area_targets = if glass_edges > 0 {
        crate::caustics::area_targets(scene).len()
    } else {
        0
    };
    let area_photons = options.caustics
        && !tracing_light
        && specular_paths
        && areas > 0
        && glass_edges > 0
        && area_targets <= crate::caustics::MAX_AREA_TARGETS
        && !scene
            .lights
            .iter()
            .any(|l| matches!(l.shape, crate::scene::LightShape::Arc { .. }));
    // Past its last diffuse bounce a path goes on only where such a
    // light could be met, and photons do not take it; not forced, as
    // it would find none.
    let last_legs = indirect && specular_paths && areas > 0 && !area_photons;
    // Path tracing cannot find their light after a mirror or glass
    // (where no closed form takes all of it), and leaves it to photons
    // off a rough mirror at a path's first bounce (where a narrow lobe
    // makes paths noisy): the caustic pass does, wherever both are in
    // the scene.
    // A laser's light no path finds at all: the caustic pass takes it
    // wherever the scene has one.
    let aimed_specular = specular_paths && !aimed_runs_closed;
    let caustics = options.caustics
        && !tracing_light
        && !no_lights
        && (((aimed_specular || glossy_paths) && aimed > 0) || lasers > 0 || area_photons);
    Transport {
        indirect_possible,
        indirect,
        mirror_emission,
        area_targets,
        area_photons,
        last_legs,
        caustics,
    }
}

/// How the floor's direct and indirect light are estimated
/// ([`floor_decisions`]).
struct FloorDecisions {
    light_table: bool,
    floor_memo: bool,
    floor_squares: bool,
    floor_lines: bool,
    absorbing_glass: usize,
    line_piece_tenths: u32,
    dense_walls: bool,
}

/// The plan's decisions for the floor: the light table, the floor memo
/// and its squares, and the lines across the image.
fn floor_decisions(
    scene: &Scene,
    options: &RenderOptions,
    inventory: &Inventory,
    transport: &Transport,
) -> FloorDecisions {
    let tracing_light = options.integrator == Integrator::Light;
    let no_lights = scene.lights.is_empty();
    // Path tracing's next-event estimation, wherever it runs, takes
    // the table's lights in a scene of many (the same in the reference:
    // it is the estimator, not a fast path).
    let light_table = !tracing_light
        && match options.light_choice {
            LightChoice::Auto => scene.lights.len() > MANY_LIGHTS,
            LightChoice::Every => false,
            LightChoice::Table => !no_lights,
        };
    // Points, spots and suns over each pixel's square in closed form,
    // where the floor's direct light is estimated once per pixel.
    let squares = !light_table
        && scene
            .lights
            .iter()
            .any(|l| crate::estimators::square::takes_square(&l.shape));
    // The floor memo runs where paths reuse it, and where the squares
    // make a pixel's direct light exact at shadow edges. The reference
    // never changes how the floor's direct light is estimated: that
    // would change the image.
    let floor_memo = !tracing_light
        && options.memo.enabled
        && ((transport.indirect_possible && inventory.reflectors > 0)
            || (squares && inventory.occluders > 0));
    let floor_squares = floor_memo && squares;
    let absorbing_glass = scene
        .glass
        .iter()
        .filter(|g| g.absorption != crate::Rgb::ZERO)
        .count();
    let (width, height) = crate::options::image_size(scene, options.scale);
    let line_pieces = crate::lines::pieces_per_pixel(scene, (width, height));
    let dense_walls = line_pieces > crate::lines::MAX_PIECES_PER_PIXEL;
    let line_piece_tenths = (10.0 / line_pieces).round().min(u32::MAX as f64) as u32;
    let floor_lines = floor_memo
        && transport.indirect
        && options.floor_lines
        && !dense_walls
        && options.integrator == Integrator::Path
        && !options.adaptive
        && absorbing_glass == 0;
    FloorDecisions {
        light_table,
        floor_memo,
        floor_squares,
        floor_lines,
        absorbing_glass,
        line_piece_tenths,
        dense_walls,
    }
}

/// What [`memo_decisions`] reads of the scene and of the plan's earlier
/// decisions.
struct MemoFacts {
    tracing_light: bool,
    indirect: bool,
    force: bool,
    diffuse: usize,
    reflectors: usize,
    glass_edges: usize,
}

/// Whether the wall memo fits its budget, whether it runs, and whether
/// the onward memo does.
fn memo_decisions(scene: &Scene, options: &RenderOptions, facts: MemoFacts) -> (bool, bool, bool) {
    let MemoFacts {
        tracing_light,
        indirect,
        force,
        diffuse,
        reflectors,
        glass_edges,
    } = facts;
    let wall_memo_wanted = !tracing_light
        && indirect
        && options.bounces > 0
        && options.memo.enabled
        && (force || (diffuse > 0 && reflectors > 0));
    // Counted before anything is allocated; over its budget the memo
    // is off (the same image, estimated by shadow rays).
    let wall_memo_bytes = wall_memo_wanted
        .then(|| {
            crate::memo::wall_memo_bytes(
                scene,
                &options.memo,
                options.scale,
                crate::memo::WALL_MEMO_BUDGET,
            )
        })
        .flatten();
    let wall_memo_fits = !wall_memo_wanted || wall_memo_bytes.is_some();
    let wall_memo = wall_memo_wanted && wall_memo_fits;
    // The rest of a path read at its first diffuse wall: where paths
    // take more than one reflection, through no glass body (whose
    // inside a wall's bins cannot tell), within its budget.
    let onward = wall_memo
        && options.memo.onward
        && options.integrator == Integrator::Path
        && options.bounces >= 2
        && glass_edges == 0
        && wall_memo_bytes.is_some_and(|bytes| {
            crate::onward::onward_bytes(bytes, options.bounces) <= crate::onward::ONWARD_BUDGET
        });
    (wall_memo_fits, wall_memo, onward)
}
