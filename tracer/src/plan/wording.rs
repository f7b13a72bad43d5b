//! What the plan says to a user: each effect, whether it runs, and why,
//! in plain words, from the plan's inventory and decisions.

use std::fmt;

use super::{Inventory, Plan};
use crate::options::{LightChoice, MANY_LIGHTS};
use crate::run::ROULETTE_FROM;

/// One effect: whether it runs, and a reason in plain words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Effect {
    pub name: &'static str,
    pub runs: bool,
    pub why: String,
}

/// Effects that say how the work is done rather than what is simulated:
/// printed only in the verbose plan.
const INTERNAL: [&str; 8] = [
    "cache: floor strata share shadow rays",
    "floor rays: walls culled by direction",
    "cache: floor points light by light",
    "one bounce read from the wall cache",
    "floor albedo along walls from a table",
    "pixel loop compiled for AVX2",
    "light table: dark cells",
    "ray queries",
];

impl Effect {
    /// Whether the effect is about how the work is done (culling, shared
    /// rays, the kind of ray queries), not about what is simulated.
    pub fn is_internal(&self) -> bool {
        INTERNAL.contains(&self.name)
    }
}

/// What the plan adds to the lines of points, spots and suns where the
/// floor memo takes them over each pixel's square (`Plan::floor_squares`).
const OVER_THE_SQUARE: &str = "; on the floor, each pixel's mean over its square in closed form";

impl Plan {
    /// Every effect with its reason, in a fixed order, for printing.
    pub fn effects(&self) -> Vec<Effect> {
        let mut effects = Vec::new();
        self.direct_effects(&mut effects);
        self.shadow_effects(&mut effects);
        self.indirect_effects(&mut effects);
        self.closed_form_effects(&mut effects);
        self.seen_effects(&mut effects);
        self.wall_effects(&mut effects);
        self.wall_cache_effects(&mut effects);
        self.floor_cache_effects(&mut effects);
        self.photon_effects(&mut effects);
        self.glass_effects(&mut effects);
        self.work_effects(&mut effects);
        effects
    }

    /// The floor's direct light, by kind of light.
    fn direct_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            points,
            spots,
            lines,
            circles,
            suns,
            beams,
            lasers,
            arcs,
            ..
        } = self.inventory;
        let Plan {
            tracing_light,
            caustics,
            floor_squares,
            ..
        } = *self;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "direct light: points and spots",
            points + spots > 0,
            if points + spots > 0 {
                format!(
                    "{}, {}{}",
                    n(points, "point light"),
                    n(spots, "spot light"),
                    if floor_squares { OVER_THE_SQUARE } else { "" }
                )
            } else {
                "no point or spot light in the scene".into()
            },
        );
        add(
            "direct light: lines and circles",
            lines + circles > 0,
            match (lines, circles) {
                (0, 0) => "no line or circle light in the scene".into(),
                (_, 0) => n(lines, "line light"),
                (0, _) => n(circles, "circle light"),
                _ => format!("{}, {}", n(lines, "line light"), n(circles, "circle light")),
            },
        );
        add(
            "direct light: sunlight",
            suns + beams > 0,
            match (suns, beams) {
                (0, 0) => "no directional light in the scene".into(),
                (_, 0) if floor_squares => {
                    format!("{}{OVER_THE_SQUARE}", n(suns, "directional light"))
                }
                (_, 0) => n(suns, "directional light"),
                (0, _) => n(beams, "beam"),
                _ => format!("{}, {}", n(suns, "directional light"), n(beams, "beam")),
            },
        );
        if arcs > 0 {
            // Said only where the scene has an arc: no other plan changes.
            add(
                "curved walls: exact ray-arc crossings",
                true,
                format!(
                    "{}; a ray can meet one twice, and meets the one it leaves again where it curves back",
                    n(arcs, "arc")
                ),
            );
        }
        if lasers > 0 {
            // Said only where the scene has a laser: no other plan changes.
            add(
                "lasers: light tracing and the caustic pass only",
                tracing_light || caustics,
                if tracing_light {
                    format!("light tracing follows {}", n(lasers, "laser"))
                } else if caustics {
                    format!(
                        "{}: a ray no path from the floor finds, so the caustic pass traces all of its light",
                        n(lasers, "laser")
                    )
                } else {
                    "the caustic pass is switched off (--caustics off): path tracing alone cannot see a laser".into()
                },
            );
        }
    }

    /// Shadow rays, and the lights each point's rays go to.
    fn shadow_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            lights, occluders, ..
        } = self.inventory;
        let Plan {
            tracing_light,
            shadows,
            light_choice,
            light_table,
            ref fast,
            reference,
            ..
        } = *self;
        let force = reference;
        let no_lights = self.inventory.lights == 0;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "shadow rays",
            shadows,
            if tracing_light {
                "light tracing casts none".into()
            } else if no_lights {
                "no light in the scene".into()
            } else if occluders > 0 {
                format!("{} can occlude", n(occluders, "wall"))
            } else if force {
                "forced on (nothing occludes)".into()
            } else {
                "nothing occludes: no wall, or only clear transparent walls".into()
            },
        );
        add(
            "shadow rays to chosen lights",
            light_table,
            if tracing_light {
                "light tracing casts none".into()
            } else if no_lights {
                "no light in the scene".into()
            } else if light_table {
                let dark = fast.dark_cells.runs;
                format!(
                    "{}: at each point, the up to {} brightest there (estimated per cell of the plan), and at most one more drawn at random by what each brings{}",
                    n(lights, "light"),
                    crate::estimators::choice::ALWAYS,
                    if dark {
                        " (no shadow ray to one that a wall hides from the whole cell)"
                    } else {
                        ""
                    }
                )
            } else if light_choice == LightChoice::Every {
                "one shadow ray to every light (--lights every)".into()
            } else {
                format!(
                    "{}, at most {MANY_LIGHTS}: one shadow ray to every light",
                    n(lights, "light")
                )
            },
        );
    }

    /// Indirect light, and the mirrors that pass it on.
    fn indirect_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            mirrors,
            rough_mirrors,
            reflectors,
            ..
        } = self.inventory;
        let Plan {
            bounces,
            specular: specular_limit,
            indirect,
            reference,
            ..
        } = *self;
        let force = reference;
        let no_lights = self.inventory.lights == 0;
        let specular = self.inventory.mirrors + self.inventory.glass_edges;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        // Mirrors and glass pass light on: by paths from the floor, by
        // the caustic pass, or by the light tracer's photons.
        let specular_runs = self.specular_runs();
        add(
            "indirect light",
            indirect,
            if no_lights {
                "no light in the scene".into()
            } else if bounces == 0 && !(specular > 0 && specular_limit > 0) {
                "bounces = 0, and no mirror or glass passes light on".into()
            } else if bounces == 0 && !indirect {
                "bounces = 0: no path from the floor can bring light back (no line or circle light to see in a mirror)".into()
            } else if reflectors == 0 && !force {
                "no wall reflects light (none, all transparent, or all black)".into()
            } else if bounces == 0 {
                format!(
                    "bounces = 0: only lines and circles seen in mirrors or glass, {}",
                    runs_of(specular_limit)
                )
            } else {
                format!(
                    "up to {} off walls, and {}",
                    n(bounces as usize, "diffuse bounce"),
                    runs_of(specular_limit)
                )
            },
        );
        let specular_why = |count: usize, what: &str| self.specular_why(count, what);
        add(
            "mirrors",
            specular_runs && mirrors > 0,
            specular_why(mirrors, "mirror"),
        );
        add(
            "rough mirrors",
            indirect && bounces > 0 && rough_mirrors > 0,
            if rough_mirrors == 0 {
                "no rough mirror in the scene".into()
            } else if bounces == 0 {
                "bounces = 0: a rough mirror's reflection is a bounce".into()
            } else if !indirect {
                "no indirect light is traced".into()
            } else {
                n(rough_mirrors, "rough mirror")
            },
        );
    }

    /// The closed forms through mirrors and glass
    /// (`estimators::ClosedForms`), each as it gives its reason.
    fn closed_form_effects(&self, effects: &mut Vec<Effect>) {
        for (name, decision) in self.closed_forms.named() {
            effects.push(Effect {
                name,
                runs: decision.runs,
                why: decision.why.clone(),
            });
        }
    }

    /// Lines and circles seen in mirrors and through glass by path rays.
    fn seen_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            areas,
            rough_mirrors,
            ..
        } = self.inventory;
        let Plan {
            bounces,
            indirect,
            mirror_emission,
            ..
        } = *self;
        let specular = self.inventory.mirrors + self.inventory.glass_edges;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let glossy = rough_mirrors > 0 && bounces > 0;
        add(
            "lines and circles seen in mirrors or glass",
            mirror_emission,
            if mirror_emission && !((specular > 0 || glossy) && areas > 0) {
                "forced on".into()
            } else if mirror_emission {
                match (specular > 0, glossy) {
                    (true, false) => "mirrors or glass, and line or circle lights, in the scene",
                    (false, _) => "rough mirrors, and line or circle lights, in the scene",
                    (true, true) => {
                        "mirrors or glass, rough mirrors, and line or circle lights, in the scene"
                    }
                }
                .into()
            } else if !indirect {
                "no indirect light is traced".into()
            } else if specular == 0 && !glossy {
                "no mirror or glass in the scene".into()
            } else {
                "no line or circle light in the scene".into()
            },
        );
    }

    /// Transparent walls, and walls that take the floor's albedo.
    fn wall_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            panes,
            diffuse,
            floor_albedo_walls,
            ..
        } = self.inventory;
        let Plan { indirect, .. } = *self;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "transparency",
            panes > 0,
            if panes > 0 {
                n(panes, "transparent wall")
            } else {
                "no transparent wall in the scene".into()
            },
        );
        add(
            "colour bleeding from the floor",
            indirect && floor_albedo_walls > 0,
            if diffuse == 0 {
                "no diffuse wall in the scene".into()
            } else if floor_albedo_walls == 0 {
                "every diffuse wall has its own albedo".into()
            } else if !indirect {
                "no indirect light is traced".into()
            } else {
                format!("{} take the floor's albedo", n(floor_albedo_walls, "wall"))
            },
        );
    }

    /// The caches of light on walls.
    fn wall_cache_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            glass_edges,
            diffuse,
            ..
        } = self.inventory;
        let Plan {
            bounces,
            tracing_light,
            memo_enabled,
            ref bin_length,
            wall_memo_fits,
            indirect,
            wall_memo,
            onward,
            original,
            onward_enabled,
            reference,
            ..
        } = *self;
        let force = reference;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "cache: wall irradiance",
            wall_memo,
            if tracing_light {
                "light tracing does not read it".into()
            } else if !memo_enabled {
                "the cache is switched off (--cache off)".into()
            } else if !indirect {
                "no indirect light is traced, so no path reads it".into()
            } else if diffuse == 0 && !force {
                "no diffuse wall to cache".into()
            } else if !wall_memo_fits {
                format!(
                    "its bins would take more than its budget of {} MiB (walls that cross often, or a short cache_bin): shadow rays instead",
                    crate::memo::WALL_MEMO_BUDGET >> 20
                )
            } else {
                format!(
                    "{} binned every {} pixel; one read in {} checked by shadow rays, so that the bins' bias falls out; one in 8, 4 or 2, or every one, where the bins may be further off (a shadow's edge, a lamp close to a wall, a span's end)",
                    n(diffuse, "diffuse wall"),
                    bin_length,
                    flatray_cache::CHECK_RATE
                )
            },
        );
        add(
            "cache: light between walls",
            onward,
            if tracing_light {
                "light tracing does not read it".into()
            } else if !indirect {
                "no indirect light is traced".into()
            } else if bounces < 2 {
                "one bounce: no light goes on from a wall".into()
            } else if !memo_enabled {
                "the cache is switched off (--cache off)".into()
            } else if !wall_memo {
                "no wall cache".into()
            } else if original {
                "the original estimator follows its paths".into()
            } else if !onward_enabled {
                "the cache holds direct light only (--cache direct): paths are followed".into()
            } else if glass_edges > 0 {
                "glass in the scene: paths are followed through it".into()
            } else if !onward {
                format!(
                    "its tables would take more than its budget of {} MiB: paths are followed",
                    crate::onward::ONWARD_BUDGET >> 20
                )
            } else {
                format!(
                    "what the rest of a path brings from each diffuse wall (up to {} more), binned every {} pixel: paths end at their first diffuse wall",
                    n(bounces as usize - 1, "reflection"),
                    bin_length
                )
            },
        );
    }

    /// The cache of the floor's direct light, and the floor's lines.
    fn floor_cache_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory { .. } = self.inventory;
        let Plan {
            tracing_light,
            memo_enabled,
            floor_points,
            indirect,
            original,
            floor_memo,
            floor_coherence,
            floor_squares,
            floor_lines,
            lines_enabled,
            adaptive,
            absorbing_glass,
            line_piece_tenths,
            dense_walls,
            light_table,
            ref fast,
            ..
        } = *self;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "cache: floor direct light per pixel",
            floor_memo,
            if tracing_light {
                "light tracing does not read it".into()
            } else if !memo_enabled {
                "the cache is switched off (--cache off)".into()
            } else if !indirect && floor_squares {
                format!(
                    "for the points', spots' and suns' means over each pixel's square, exact at shadow edges: {floor_points} stratified points per pixel in the first pass, then as many as its noise asks"
                )
            } else if !indirect {
                "no indirect path would reuse it".into()
            } else if light_table {
                format!(
                    "{floor_points} stratified points per pixel in the first pass (one a sample: a light table draws each point's lights), then as many as its noise asks"
                )
            } else {
                format!(
                    "{floor_points} stratified points per pixel in the first pass (each point's direct light is exact), then as many as its noise asks"
                )
            },
        );
        add(
            "floor's indirect light along lines",
            floor_lines,
            if tracing_light {
                "light tracing follows its photons instead".into()
            } else if !indirect {
                "no indirect light is traced".into()
            } else if !floor_memo {
                "without the floor cache, each pixel's path samples take the floor's light".into()
            } else if original {
                "the original estimator takes one uniform bounce per sample".into()
            } else if !lines_enabled {
                "switched off (--indirect samples): each pixel's path samples take it".into()
            } else if adaptive {
                "adaptive passes: each pixel's path samples take it, where the passes go".into()
            } else if absorbing_glass > 0 {
                format!(
                    "{} absorbs: each pixel's path samples take it",
                    n(absorbing_glass, "glass body")
                )
            } else if dense_walls {
                format!(
                    "walls so dense that a line would be cut every {:.1} pixels: each pixel's path samples take it",
                    line_piece_tenths as f64 / 10.0
                )
            } else {
                "lines across the image in stratified directions, each piece between two walls looking both ways: pixels take no path samples".into()
            },
        );
        add(
            "cache: floor strata share shadow rays",
            floor_coherence,
            fast.coherence.why.clone(),
        );
    }

    /// The photon passes through mirrors and glass.
    fn photon_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            beams,
            lasers,
            aimed,
            areas,
            glass_edges,
            specular_reflectors,
            ..
        } = self.inventory;
        let Plan {
            specular: specular_limit,
            tracing_light,
            caustics_enabled,
            area_photons,
            area_targets,
            caustics,
            aimed_runs_closed,
            ..
        } = *self;
        let specular = self.inventory.mirrors + self.inventory.glass_edges;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "points, spots and sun seen in mirrors or glass",
            (caustics && aimed > 0)
                || (aimed_runs_closed && aimed > 0 && specular_reflectors > 0)
                || (tracing_light && specular_limit > 0 && specular > 0 && aimed > 0),
            if specular == 0 {
                "no mirror or glass in the scene".into()
            } else if aimed == 0 {
                "no point, spot or directional light in the scene".into()
            } else if specular_limit == 0 {
                "specular = 0: light stops at mirrors and glass".into()
            } else if specular_reflectors == 0 {
                "every mirror is black: no light goes on from one".into()
            } else if tracing_light {
                "light tracing follows their light through mirrors and glass".into()
            } else if aimed_runs_closed && !caustics {
                format!(
                    "{}: all their light off it is taken in closed form (points, spots and suns in a mirror), so no photon pass is traced",
                    match specular_reflectors {
                        1 => "1 flat mirror".to_string(),
                        n => format!("{n} flat mirrors, all on one line"),
                    }
                )
            } else if !caustics_enabled {
                "the caustic pass is switched off (--caustics off): path tracing alone cannot see them".into()
            } else {
                format!(
                    "a photon pass from {} towards {} (the parts walls do not hide): their light on the floor by track length, on diffuse walls in bins; fewer photons where these take under a quarter of the lights' power",
                    n(
                        aimed,
                        if beams + lasers > 0 {
                            "point, spot, directional light, beam or laser"
                        } else {
                            "point, spot or directional light"
                        }
                    ),
                    n(specular, "mirror or glass edge")
                )
            },
        );
        add(
            "lines and circles after mirrors and glass, photons",
            area_photons,
            if area_photons {
                format!(
                    "photons from {} aimed at {} of mirrors and glass: their light after every run of mirror and glass events from the floor or a diffuse wall but one taken in closed form, on the floor by track length, on diffuse walls in bins; path rays add none of it",
                    n(areas, "line or circle light"),
                    n(area_targets, "segment")
                )
            } else if tracing_light {
                "light tracing follows their light through mirrors and glass".into()
            } else if areas == 0 {
                "no line or circle light in the scene".into()
            } else if glass_edges == 0 {
                "no glass in the scene: path rays find them after mirrors".into()
            } else if specular_limit == 0 {
                "specular = 0: light stops at mirrors and glass".into()
            } else if !caustics_enabled {
                "the caustic pass is switched off (--caustics off): path rays find them".into()
            } else if area_targets > crate::caustics::MAX_AREA_TARGETS {
                format!(
                    "{}, over {}: path rays find them",
                    n(area_targets, "mirror or glass segment"),
                    crate::caustics::MAX_AREA_TARGETS
                )
            } else {
                "an arc light in the scene: path rays find them".into()
            },
        );
    }

    /// Glass and its dispersion.
    fn glass_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            glass_edges,
            glass_bodies,
            dispersive,
            rough_glass,
            spectral,
            ..
        } = self.inventory;
        let specular_runs = self.specular_runs();
        let limit_said = self.limit_said();
        let specular_why = |count: usize, what: &str| self.specular_why(count, what);
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "glass",
            specular_runs && glass_edges > 0,
            if glass_edges == 0 {
                "no glass in the scene".into()
            } else if !specular_runs {
                specular_why(glass_edges, "glass edge")
            } else {
                let rough = match rough_glass {
                    0 => String::new(),
                    r if r == glass_bodies => " (rough: each event spreads its light)".into(),
                    r => format!(" ({r} rough: each event spreads its light)"),
                };
                format!(
                    "{}{rough} in {} edges{limit_said}",
                    n(glass_bodies, "glass body"),
                    glass_edges,
                )
            },
        );
        add(
            "dispersion (wavelength per path)",
            specular_runs && glass_edges > 0 && dispersive > 0,
            if dispersive == 0 {
                "no dispersive glass in the scene".into()
            } else if !specular_runs {
                specular_why(glass_edges, "glass edge")
            } else if spectral > 0 {
                format!(
                    "{}; {} with a spectrum, their light wavelength by wavelength",
                    n(dispersive, "dispersive glass body"),
                    n(spectral, "light")
                )
            } else {
                n(dispersive, "dispersive glass body")
            },
        );
    }

    /// How the work is done: culling, the fast paths, the ray queries.
    fn work_effects(&self, effects: &mut Vec<Effect>) {
        let Inventory {
            walls, ref queries, ..
        } = self.inventory;
        let Plan {
            floor_ray_culling,
            ref fast,
            ..
        } = *self;
        let mut add =
            |name: &'static str, runs: bool, why: String| effects.push(Effect { name, runs, why });
        let n = counted;
        add(
            "floor rays: walls culled by direction",
            floor_ray_culling,
            fast.culling.why.clone(),
        );
        for (name, decision) in [
            ("cache: floor points light by light", &fast.strata_loops),
            ("one bounce read from the wall cache", &fast.shortcut),
            ("floor albedo along walls from a table", &fast.tables),
            ("pixel loop compiled for AVX2", &fast.avx),
            ("light table: dark cells", &fast.dark_cells),
        ] {
            add(name, decision.runs, decision.why.clone());
        }
        add(
            "ray queries",
            walls > 0,
            if walls == 0 {
                "no walls".into()
            } else {
                format!("{}: {}", n(walls, "wall"), queries)
            },
        );
    }
}

impl Plan {
    /// The plan for a user: the effects simulated and skipped, without how
    /// the work is done ([`Plan::verbose`], and `Display`, have it all).
    pub fn summary(&self) -> impl fmt::Display + '_ {
        PlanText {
            plan: self,
            verbose: false,
        }
    }

    /// Every effect, the internal ones too.
    pub fn verbose(&self) -> impl fmt::Display + '_ {
        PlanText {
            plan: self,
            verbose: true,
        }
    }
}

struct PlanText<'a> {
    plan: &'a Plan,
    verbose: bool,
}

impl fmt::Display for PlanText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let effects = self.plan.effects();
        let shown = || effects.iter().filter(|e| self.verbose || !e.is_internal());
        let width = shown().map(|e| e.name.len()).max().unwrap_or(0);
        for (k, e) in shown().enumerate() {
            if k > 0 {
                writeln!(f)?;
            }
            let mark = if e.runs { "runs   " } else { "skipped" };
            write!(f, "{mark}  {:<width$}  {}", e.name, e.why)?;
        }
        Ok(())
    }
}

/// Every effect, as [`Plan::verbose`].
impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.verbose().fmt(f)
    }
}

/// `k` things called `what`, in the plural where `k` is not 1.
fn counted(k: usize, what: &str) -> String {
    if k == 1 {
        format!("{k} {what}")
    } else if let Some(stem) = what.strip_suffix("body") {
        format!("{k} {stem}bodies")
    } else {
        format!("{k} {what}s")
    }
}

impl Plan {
    /// Whether mirrors and glass pass light on: by paths from the floor,
    /// by the caustic pass, or by the light tracer's photons.
    fn specular_runs(&self) -> bool {
        self.specular > 0 && (self.indirect || self.caustics || self.tracing_light)
    }

    /// The limit of specular events, said once: with the indirect light
    /// where it runs, else with the mirrors' and glass's own lines.
    fn limit_said(&self) -> String {
        if self.indirect {
            String::new()
        } else {
            format!(", {}", runs_of(self.specular))
        }
    }

    /// Why mirrors or glass (`count` of `what`) pass light on or not.
    fn specular_why(&self, count: usize, what: &str) -> String {
        if count == 0 {
            format!("no {what} in the scene")
        } else if self.specular == 0 {
            "specular = 0: light stops at mirrors and glass".into()
        } else if !self.specular_runs() {
            "no indirect light is traced".into()
        } else {
            format!("{}{}", counted(count, what), self.limit_said())
        }
    }
}

/// A run of at most `limit` specular events, in words.
fn runs_of(limit: u32) -> String {
    format!(
        "up to {} in a row (Russian roulette past {ROULETTE_FROM})",
        counted(limit as usize, "mirror or glass event")
    )
}
