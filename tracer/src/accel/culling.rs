//! A fast path: the walls each block of pixels' rays can meet, per arc of
//! directions, and the walls its floor points' shadow rays towards each
//! light can cross. The pixel loop (`pixel.rs`) tests only those, through
//! the geometry's listed queries: the same answers as the whole set.

use flatray_geometry::{ArcCandidates, DVec2, hull_candidates};

use crate::estimators::choice::LightTable;
use crate::options::{LONG_LIST, TILE_SHADOW_TESTS};
use crate::sampling::ARCS;
use crate::scene::Scene;

/// What a block of pixels culls: for each arc of directions, the walls its
/// floor rays can meet; for each light, the walls the shadow rays from its
/// floor points can cross (`None` for a sun: every wall).
#[derive(Default)]
pub(crate) struct BlockCulling {
    pub(crate) arcs: ArcCandidates,
    pub(crate) shadows: Vec<Option<Vec<u32>>>,
}

impl BlockCulling {
    /// The lists for the block `[lo, hi]` of tile `tile`; the shadow lists
    /// only when shadow rays are cast.
    pub(crate) fn fill(
        &mut self,
        scene: &Scene,
        lo: DVec2,
        hi: DVec2,
        tile: &ArcCandidates,
        shadows: bool,
    ) {
        self.arcs.fill(&scene.segments, lo, hi, ARCS, Some(tile));
        self.fill_shadows(scene, lo, hi, shadows);
    }

    /// Shadow rays whose list holds more walls than this ask the BVH: the
    /// same answer, for less work than a long list.
    pub(crate) fn drop_long_shadow_lists(&mut self) {
        for list in &mut self.shadows {
            if list.as_ref().is_some_and(|l| l.len() > LONG_LIST) {
                *list = None;
            }
        }
    }

    /// The shadow lists for the block `[lo, hi]` (only when shadow rays
    /// are cast). Without `shadows`, the lists stay as they are: those of
    /// the block's tile, or none.
    pub(crate) fn fill_shadows(&mut self, scene: &Scene, lo: DVec2, hi: DVec2, shadows: bool) {
        self.shadows.resize(scene.lights.len(), None);
        if shadows {
            self.fill_shadows_of(scene, lo, hi, |_| true);
        }
    }

    /// The shadow lists for the block `[lo, hi]` of the lights that
    /// `listed` takes; the other lights have none.
    pub(crate) fn fill_shadows_of(
        &mut self,
        scene: &Scene,
        lo: DVec2,
        hi: DVec2,
        listed: impl Fn(usize) -> bool,
    ) {
        self.shadows.resize(scene.lights.len(), None);
        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
        for (index, (light, list)) in scene.lights.iter().zip(&mut self.shadows).enumerate() {
            let hull = light.shape.hull().filter(|_| listed(index));
            let Some(hull) = hull else {
                *list = None;
                continue;
            };
            let points = [
                corners[0], corners[1], corners[2], corners[3], hull[0], hull[1], hull[2], hull[3],
            ];
            hull_candidates(&scene.segments, &points, list.get_or_insert_with(Vec::new));
        }
    }
}

/// Marks in `listed` the lights whose shadow rays from the tile `[lo, hi]`
/// take a list: every light where lights times walls fit
/// [`TILE_SHADOW_TESTS`]; else those that the table's cells under the tile
/// take at every point or by what their probes saw, or else their
/// always-lights alone, as long as they fit; else none (the BVH answers).
pub(crate) fn tile_lights(
    scene: &Scene,
    table: &LightTable,
    tile: (DVec2, DVec2),
    listed: &mut Vec<bool>,
) {
    let walls = scene.walls.len().max(1);
    let lights = scene.lights.len();
    listed.clear();
    if lights * walls <= TILE_SHADOW_TESTS {
        listed.resize(lights, true);
        return;
    }
    if table.lights_in_box(tile, true, listed) * walls <= TILE_SHADOW_TESTS
        || table.lights_in_box(tile, false, listed) * walls <= TILE_SHADOW_TESTS
    {
        return;
    }
    listed.clear();
    listed.resize(lights, false);
}

/// Where the culling lists pay: path tracing with indirect rays, walls
/// to cull and not so many that the BVH alone answers best.
pub(crate) fn supports(facts: &crate::accel::Facts) -> crate::accel::Decision {
    use crate::accel::Decision;
    use crate::accel::mirror::{GATHER_PIECE, MIRROR_PIECE};
    use crate::options::{CULL_BLOCK, FINE_CULLING_SAMPLES, FastPath, MAX_CULLED_WALLS, TILE};
    if facts.tracing_light {
        return Decision::skipped("light tracing casts none");
    }
    if !facts.indirect {
        return Decision::skipped("no indirect light is traced");
    }
    if facts.walls == 0 {
        return Decision::skipped("no walls");
    }
    if facts.walls > MAX_CULLED_WALLS {
        return Decision::skipped(format!(
            "more than {MAX_CULLED_WALLS} walls: the BVH answers every ray"
        ));
    }
    if let Some(no) = Decision::allowed(facts.options, FastPath::Culling, "culling") {
        return no;
    }
    let off_mirrors = if facts.mirrors > 0 {
        format!(", and so for rays off mirrors per {MIRROR_PIECE} pixels of mirror")
    } else {
        String::new()
    };
    let gathers = if facts.onward {
        format!(", and for the onward memo's gathers per {GATHER_PIECE} pixels of wall")
    } else {
        String::new()
    };
    let shadow_lists = if !facts.shadows {
        String::new()
    } else if facts.light_table && facts.lights * facts.walls <= TILE_SHADOW_TESTS {
        format!(
            "; the chosen lights' shadow rays, only the walls between the {TILE}x{TILE} tile and the light"
        )
    } else if facts.light_table {
        format!(
            "; the shadow rays of the lights a {TILE}x{TILE} tile's cells take most, only the walls between the tile and the light (at most {TILE_SHADOW_TESTS} wall tests a tile)"
        )
    } else {
        "; the floor cache's shadow rays, only the walls between the pixels and the light".into()
    };
    Decision::runs(format!(
        "per {CULL_BLOCK}x{CULL_BLOCK} pixels (per {TILE}x{TILE} below {FINE_CULLING_SAMPLES} samples) and 1/{ARCS} turn, only the walls such rays can meet before an opaque one{off_mirrors}{gathers}; a ray whose list holds more than {LONG_LIST} asks the whole set{shadow_lists}"
    ))
}
