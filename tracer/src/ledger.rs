//! The ledger of light transport: which estimator counts which light path.
//!
//! A light path, read from the light to the floor, is a light and a list
//! of vertices: specular events (mirrors, glass), glossy reflections
//! (rough mirrors) and diffuse reflections. The estimators of
//! `docs/model.md` (next-event estimation at receivers, the closed forms
//! through one mirror or one glass edge, path rays that meet a light, the
//! caustic pass's floor deposits and wall bins) each count some of these
//! paths; every path within the limits must be counted exactly once, or
//! shared by weights that sum to one (multiple importance sampling at a
//! rough mirror). The rule that decides it is written here: the path
//! loop (`path.rs`), the photon loop (`light_tracer.rs`) and glossy
//! next-event estimation ask the [`Ledger`] the plan built
//! (`Plan::ledger`). The receivers' direct-light sums take the closed
//! forms that [`Ledger::closed_form`] names, by the plan's same
//! decisions (`Plan::closed_forms`, each closed form's own).
//!
//! The tests walk every class of path up to six events, for every kind of
//! light and every combination of the plan's decisions, through the same
//! rules, and check that each is counted once.
//!
//! What it never does: trace a ray or read a scene. It answers from a
//! path's history as the loops describe it.

use crate::scene::{Material, Wall};
use flatray_geometry::Side;

/// The decisions of a render's plan that say who counts which path.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Ledger {
    /// Receivers take line and circle lights seen in one flat mirror in
    /// closed form (`estimators::exact::through_mirrors`).
    pub mirror_lights: bool,
    /// Receivers take points, spots, suns and beams seen in one flat
    /// mirror in closed form (`estimators::mirrored`).
    pub aimed_mirrors: bool,
    /// Receivers inside glass take line and circle lights through one edge
    /// of their body in closed form (`estimators::refracted`).
    pub glass_lights: bool,
    /// The caustic pass takes line and circle lights after runs of
    /// specular events that no closed form takes (`lights::aimed`).
    pub area_photons: bool,
    /// The caustic pass runs: points, spots, suns, beams and lasers after
    /// mirrors and glass, and off a path's first rough mirror.
    pub caustics: bool,
    /// Most diffuse (and glossy) reflections.
    pub bounces: u32,
}

/// A kind of light, as the ledger tells them apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum LightKind {
    /// One direction per point (a point, spot, sun or beam): found by
    /// shadow rays straight, never by a path ray.
    Aimed,
    /// A laser: one ray, found by no path. (The photon loop knows one by
    /// [`Photon::unseen`]; the enumeration names it.)
    #[cfg_attr(not(test), allow(dead_code))]
    Laser,
    /// A line or circle (or an emitting wall): found by shadow rays, by
    /// the closed forms, and by path rays that meet it.
    Area,
}

/// A specular event, in the direction light travels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Event {
    /// A reflection off a flat, perfect mirror.
    FlatMirror,
    /// A reflection off a curved mirror (an arc).
    CurvedMirror,
    /// A refraction into a glass body.
    GlassIn,
    /// A refraction out of a glass body.
    GlassOut,
    /// A reflection at a glass edge (outside or inside).
    GlassReflect,
}

impl Event {
    /// The specular event a ray that arrived on `side` of `wall` takes
    /// there, in the direction of that ray, where it is inside a glass
    /// body afterwards if `inside_after`.
    pub(crate) fn of(wall: &Wall, side: Side, inside_after: bool) -> Event {
        let from_inside = wall
            .material
            .glass()
            .is_some_and(|(_, inside)| inside == side);
        match wall.material {
            Material::Mirror { .. } if wall.as_segment().is_some() => Event::FlatMirror,
            Material::Glass { .. } if !from_inside && inside_after => Event::GlassIn,
            Material::Glass { .. } if from_inside && !inside_after => Event::GlassOut,
            Material::Glass { .. } => Event::GlassReflect,
            _ => Event::CurvedMirror,
        }
    }

    /// The same event seen by light going the other way.
    pub(crate) fn reversed(self) -> Event {
        match self {
            Event::GlassIn => Event::GlassOut,
            Event::GlassOut => Event::GlassIn,
            other => other,
        }
    }
}

/// A scattering vertex that is not specular.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Vertex {
    /// The floor, where every path ends.
    Floor,
    /// A Lambertian wall.
    Diffuse,
    /// A rough mirror: a glossy reflection, one diffuse bounce.
    Glossy,
}

/// The specular events between a light or a non-specular vertex and the
/// next, as an estimator has seen them: how many, and the event itself
/// while there is exactly one, in the direction light travels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Run {
    events: u32,
    only: Option<Event>,
}

impl Run {
    /// A run that has taken no event yet.
    pub(crate) const EMPTY: Run = Run {
        events: 0,
        only: None,
    };

    /// The run with one more event, `event` in the direction light
    /// travels.
    #[inline]
    pub(crate) fn with(self, event: Event) -> Run {
        Run {
            events: self.events.saturating_add(1),
            only: (self.events == 0).then_some(event),
        }
    }

    /// Whether the run has taken an event.
    #[inline]
    pub(crate) fn is_specular(self) -> bool {
        self.events > 0
    }
}

/// How much of a class of paths an estimator counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Share {
    /// None of it.
    None,
    /// All of it.
    All,
    /// Next-event estimation's power-heuristic weight against a rough
    /// mirror's own sample (`direct::direct_light_glossy`).
    Light,
    /// The rough mirror's sample's weight, one minus [`Share::Light`]
    /// (`direct::glossy_emission_weight`).
    Lobe,
}

impl Share {
    /// Whether the estimator counts any of the class.
    pub(crate) fn counts(self) -> bool {
        self != Share::None
    }
}

/// What a photon of the caustic pass does at a wall that is not specular.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum AtWall {
    /// Its power is binned there at `level` (0: `Caustics::wall`, 1:
    /// `Caustics::wall_late`, which counts one reflection more), and it
    /// stops: paths take over there.
    Bin { level: u32 },
    /// It stops: paths count what it would bring.
    Stop,
    /// It takes the wall's reflection, a glossy one counted in `lobes`.
    Scatter,
}

/// A caustic photon's history, as the ledger reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Photon {
    /// Whether it comes from a line or circle light (`Ledger::area_photons`).
    pub area: bool,
    /// Whether no path finds its light at all (a laser).
    pub unseen: bool,
    /// Its run of specular events since the light or its last reflection.
    pub run: Run,
    /// Glossy reflections taken.
    pub lobes: u32,
    /// Whether its light no path can take over: a specular event (or a
    /// laser's light) before its first glossy reflection.
    pub carried: bool,
}

impl Ledger {
    /// Whether next-event estimation at a receiver of kind `at` takes the
    /// light of `light` that reaches it after `run`: in closed form through
    /// one flat mirror or one glass edge, for a line or circle light, or
    /// through one flat mirror for a point, spot, sun or beam, at the
    /// floor or a diffuse wall (a glossy wall's next-event estimation
    /// takes no light through mirrors or glass).
    #[inline]
    pub(crate) fn closed_form(self, light: LightKind, run: Run, at: Vertex) -> bool {
        at != Vertex::Glossy
            && run.events == 1
            && match (light, run.only) {
                (LightKind::Area, Some(Event::FlatMirror)) => self.mirror_lights,
                (LightKind::Area, Some(Event::GlassIn)) => self.glass_lights,
                (LightKind::Aimed, Some(Event::FlatMirror)) => self.aimed_mirrors,
                _ => false,
            }
    }

    /// Whether receivers take a closed form at their point alone
    /// (`estimators::at_point`).
    #[inline]
    pub(crate) fn takes_at_point(self) -> bool {
        self.mirror_lights || self.aimed_mirrors
    }

    /// What next-event estimation at a receiver of kind `at` takes of the
    /// light that reaches it straight from `light` (through panes at most).
    /// `first` says whether the receiver is the path's first non-specular
    /// vertex from the floor (the floor itself included).
    #[inline]
    pub(crate) fn straight(self, light: LightKind, at: Vertex, first: bool) -> Share {
        match (light, at) {
            (LightKind::Laser, _) => Share::None,
            (LightKind::Area, Vertex::Glossy) => Share::Light,
            // The caustic pass takes points, spots and suns off a path's
            // first rough mirror, where a narrow lobe makes paths noisy.
            (LightKind::Aimed, Vertex::Glossy) if first && self.caustics => Share::None,
            _ => Share::All,
        }
    }

    /// Whether next-event estimation at a rough mirror leaves the lights
    /// that aim photons to the caustic pass: at a path's first
    /// non-specular vertex (after `diffuse` reflections, that one
    /// included).
    #[inline]
    pub(crate) fn glossy_leaves_aimed(self, diffuse: u32) -> bool {
        self.straight(LightKind::Aimed, Vertex::Glossy, diffuse == 1) == Share::None
    }

    /// What a path ray that meets a line or circle light after `run` (in
    /// the direction light travels) from a vertex of kind `from` adds: none
    /// where next-event estimation at that vertex or the caustic pass took
    /// it, all of it where nothing else can, and the lobe's share off a
    /// rough mirror.
    #[inline]
    pub(crate) fn path_meets(self, run: Run, from: Vertex) -> Share {
        match (run.is_specular(), from) {
            (false, Vertex::Glossy) => Share::Lobe,
            (false, _) => Share::None,
            (true, Vertex::Glossy) => Share::All,
            (true, _) if self.closed_form(LightKind::Area, run, from) => Share::None,
            (true, _) if self.area_photons => Share::None,
            (true, _) => Share::All,
        }
    }

    /// Whether a caustic photon's flight after `photon`'s history counts
    /// on the floor.
    #[inline]
    pub(crate) fn photon_lights_floor(self, photon: &Photon) -> bool {
        // A point's light off a rough mirror, and a laser's, no receiver
        // takes; the rest counts after a run no closed form takes.
        if !photon.area && (photon.lobes > 0 || photon.unseen) {
            return true;
        }
        let light = match photon.area {
            true => LightKind::Area,
            false => LightKind::Aimed,
        };
        photon.run.is_specular() && !self.closed_form(light, photon.run, Vertex::Floor)
    }

    /// What a caustic photon with history `photon` does at a wall of kind
    /// `at` (diffuse or glossy). A photon whose light a path can take over
    /// at a diffuse wall is binned there; one that took a specular event
    /// (or is a laser's) before its first glossy reflection is light that
    /// no path finds, and it carries it on through further reflections.
    pub(crate) fn photon_at(self, photon: &Photon, at: Vertex) -> AtWall {
        let takes_lobe = !photon.area && self.bounces > 0;
        match (photon.lobes, at) {
            (0, Vertex::Glossy) if takes_lobe => AtWall::Scatter,
            (0, Vertex::Diffuse) if self.photon_lights_floor(photon) => AtWall::Bin { level: 0 },
            (1, Vertex::Glossy) if photon.carried => AtWall::Scatter,
            (1, Vertex::Diffuse) if photon.carried && self.bounces >= 2 => AtWall::Bin { level: 1 },
            (2.., _) => AtWall::Scatter,
            _ => AtWall::Stop,
        }
    }

    /// `photon` after a glossy reflection.
    #[inline]
    pub(crate) fn photon_glossy(self, photon: Photon) -> Photon {
        Photon {
            lobes: photon.lobes.saturating_add(1),
            carried: if photon.lobes == 0 {
                photon.run.is_specular() || photon.unseen
            } else {
                photon.carried
            },
            run: Run::EMPTY,
            ..photon
        }
    }

    /// Whether next-event estimation at a diffuse wall, after `diffuse`
    /// reflections of a path from the floor (that one included), adds the
    /// caustic pass's bins of `level`.
    #[inline]
    pub(crate) fn reads_bins(self, level: u32, diffuse: u32) -> bool {
        diffuse.saturating_add(level) <= self.bounces
    }
}

#[cfg(test)]
mod tests;
