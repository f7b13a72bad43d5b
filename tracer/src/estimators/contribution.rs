//! What one light gives a receiver: the light interface's sample
//! ([`crate::scene::LightShape::incident`]) times the receiver's cosine,
//! and the transmittance of the shadow ray between them. Direct light over
//! all lights (`direct.rs`), the memos and the light table build on it.

use flatray_geometry::{DVec2, Ray, Skip, Strategy};

use crate::lights::{Incident, arriving};
use crate::scene::Scene;
use crate::{Rgb, Stats};

/// Who receives the light: the floor (no cosine, every direction) or one
/// side of a wall (cosine to its normal, only that side).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Receiver<'a> {
    /// The unit normal of the receiving side; `None` for the floor.
    pub normal: Option<DVec2>,
    /// The wall the receiver lies on, skipped by its shadow rays.
    pub wall: Option<u32>,
    /// Per light, the only walls its shadow rays can cross, in index
    /// order, where that is known (floor points, culled per block of
    /// pixels: `hull_candidates`; `None` for a light without a list, a
    /// sun); `None`: every wall for every light.
    pub shadow_walls: Option<&'a [Option<Vec<u32>>]>,
}

impl<'a> Receiver<'a> {
    pub const FLOOR: Receiver<'static> = Receiver {
        normal: None,
        wall: None,
        shadow_walls: None,
    };

    /// The walls that shadow rays towards light `index` can cross, if
    /// known.
    #[inline]
    pub(crate) fn walls_towards(&self, index: usize) -> Option<&'a [u32]> {
        self.shadow_walls
            .and_then(|lists| lists.get(index))
            .and_then(|list| list.as_deref())
    }

    #[inline]
    pub(crate) fn skip(&self, light_wall: Option<u32>) -> Skip {
        Skip(
            self.wall.unwrap_or(u32::MAX),
            light_wall.unwrap_or(u32::MAX),
        )
    }
}

/// How a light's transmittance to a receiver point is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Visibility {
    /// By a shadow ray.
    Trace,
    /// Already known: 1 when the plan casts no shadow rays, or what the
    /// floor's coherence masks proved for a whole pixel.
    Known(Rgb),
}

impl Visibility {
    /// Traced when the plan casts shadow rays, else 1.
    #[inline]
    pub fn of(shadows: bool) -> Visibility {
        if shadows {
            Visibility::Trace
        } else {
            Visibility::Known(Rgb::ONE)
        }
    }
}

/// The light that reaches `x` from one light, coloured. A line or circle
/// light gives it in closed form (`estimators::exact`): every direction it
/// sends `x`, less the walls in front of it. Any other light gives its
/// [`Incident`] sample, times the receiver's cosine over its pdf, times
/// the transmittance of one shadow ray. Where `vis` is known (the plan
/// found nothing that occludes, or the floor's coherence masks know the
/// answer), no wall is looked at. `u` in `[0, 1)` is the light's number,
/// if it takes one; a line or circle light ignores it.
#[inline]
pub(crate) fn light_contribution(
    scene: &Scene,
    index: usize,
    x: DVec2,
    receiver: Receiver,
    u: f64,
    vis: Visibility,
    stats: &mut Stats,
) -> Rgb {
    let light = &scene.lights[index];
    if super::is_exact(&light.shape) {
        // A line or a circle: in closed form, with no sample (`u` unused).
        if let Some(w) = receiver.wall
            && light.shape.grazes(w, &scene.walls[w as usize].shape)
        {
            return Rgb::ZERO;
        }
        let value = crate::estimators::exact::exact_light(scene, index, x, receiver, vis, stats);
        return value.unwrap_or(Rgb::ZERO) * light.color;
    }
    weighed_contribution(scene, index, x, receiver, u, vis, stats, |_, v| {
        Some(Rgb::splat(v))
    })
}

/// [`light_contribution`] with the arriving value `v` (the light's
/// sample times the receiver's cosine over its pdf) turned into a colour
/// by `weigh(sample, v)` before the shadow ray: a BSDF's `f` and a
/// multiple importance sampling weight, at a glossy receiver. `None`: the
/// sample brings nothing, and no shadow ray is cast.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn weighed_contribution(
    scene: &Scene,
    index: usize,
    x: DVec2,
    receiver: Receiver,
    u: f64,
    vis: Visibility,
    stats: &mut Stats,
    weigh: impl FnOnce(&Incident, f64) -> Option<Rgb>,
) -> Rgb {
    let light = &scene.lights[index];
    if let Some(w) = receiver.wall
        && light.shape.grazes(w, &scene.walls[w as usize].shape)
    {
        return Rgb::ZERO;
    }
    let Some(s) = light.shape.incident(light, x, u, scene.small_radius) else {
        return Rgb::ZERO;
    };
    if s.at_the_light() {
        // The receiver sits on the light: no direction to test, nothing
        // in between. A wall gets no cosine from it.
        if receiver.normal.is_some() {
            return Rgb::ZERO;
        }
        return Rgb::splat(arriving(light.intensity, s.value, 1.0, s.pdf)) * light.color;
    }
    let cosine = match receiver.normal {
        None => 1.0,
        Some(n) => n.dot(s.dir()).max(0.0),
    };
    let v = arriving(light.intensity, s.value, cosine, s.pdf);
    if v == 0.0 {
        return Rgb::ZERO;
    }
    let Some(weighed) = weigh(&s, v) else {
        return Rgb::ZERO;
    };
    // A light that sits on a wall shines past it: its shadow rays ignore
    // that wall (for a solid line light, its own wall).
    let vis = match vis {
        Visibility::Trace => transmittance(
            scene,
            &Ray::new(x, s.to),
            s.t_max,
            receiver.skip(scene.light_wall[index]),
            receiver.walls_towards(index),
            stats,
        ),
        Visibility::Known(known) => known,
    };
    weighed * vis * light.color
}

/// What fraction of light gets along `ray` for `0 < t < t_max`: zero when
/// an opaque wall is in the way, else the product of the transparent
/// walls' tints, taken in the order of the walls' indices whatever order
/// the query visits them in, so that a BVH (near boxes first) and a list
/// or brute force (index order) give the same bits. Two tints multiply to
/// the same bits in either order; a BVH query that crosses three panes or
/// more finds them again by index, one query each. Counts one shadow ray.
/// With `walls`, only those walls are tested: the same answer when they
/// hold every wall the ray can cross.
pub(crate) fn transmittance(
    scene: &Scene,
    ray: &Ray,
    t_max: f64,
    skip: Skip,
    walls: Option<&[u32]>,
    stats: &mut Stats,
) -> Rgb {
    stats.work.shadow_rays += 1;
    stats.work.listed_shadow_rays += walls.is_some() as u64;
    let mut through = Rgb::ONE;
    let mut panes = 0u32;
    let mut blocked = false;
    let segments = &scene.segments;
    segments.for_each_crossing_within(ray, t_max, skip, walls, |index, _| {
        match scene.walls[index as usize].material.pane_tint() {
            Some(tint) => {
                through *= tint;
                panes += 1;
                through != Rgb::ZERO
            }
            // Opaque; and glass refracts: no straight shadow ray gets
            // through it.
            None => {
                through = Rgb::ZERO;
                blocked = true;
                false
            }
        }
    });
    let index_order = walls.is_some() || segments.strategy() == Strategy::BruteForce;
    if panes < 3 || blocked || index_order {
        return through;
    }
    // Each next pane by index.
    let mut through = Rgb::ONE;
    let mut after: Option<u32> = None;
    loop {
        let mut next: Option<(u32, Rgb)> = None;
        segments.for_each_crossing_within(ray, t_max, skip, walls, |index, _| {
            if let Some(tint) = scene.walls[index as usize].material.pane_tint()
                && after.is_none_or(|a| index > a)
                && next.is_none_or(|(n, _)| index < n)
            {
                next = Some((index, tint));
            }
            true
        });
        let Some((index, tint)) = next else {
            return through;
        };
        through *= tint;
        after = Some(index);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Canvas, Floor, Material, Wall};
    use flatray_geometry::Segment;

    /// Panes across a ray, in an order of indices unlike their order
    /// along it, with tints whose products round differently by order;
    /// and enough other walls for a BVH. The BVH (near boxes first), a
    /// list (index order) and brute force give the same bits, for three
    /// panes and many more.
    #[test]
    fn panes_tint_a_shadow_ray_in_index_order_whatever_the_query() {
        for panes in [3, 8, 9, 13] {
            let mut walls = Vec::new();
            for k in 0..panes {
                // Pane k at x = 1 + 3 ((k * 5) % panes): shuffled along the ray.
                let x = 1.0 + 3.0 * ((k * 5) % panes) as f64;
                let tint = Rgb::new(
                    0.1 + 0.07 * k as f64,
                    0.9 / (1.0 + k as f64),
                    0.3 + 0.01 * k as f64,
                );
                walls.push(Wall {
                    shape: Segment::new(DVec2::new(x, -1.0), DVec2::new(x, 1.0)).into(),
                    material: Material::Transparent { tint },
                });
            }
            for k in 0..40 {
                let y = 3.0 + k as f64;
                walls.push(Wall {
                    shape: Segment::new(DVec2::new(0.0, y), DVec2::new(40.0, y + 0.5)).into(),
                    material: Material::Diffuse { albedo: None },
                });
            }
            let canvas = Canvas {
                width: 50,
                height: 50,
                origin: DVec2::ZERO,
            };
            let scene = Scene::new(canvas, Floor::Color(Rgb::ONE), 0.5, walls, Vec::new())
                .expect("a valid scene");
            assert_eq!(scene.segments.strategy(), Strategy::Bvh);
            let ray = Ray::new(DVec2::new(0.0, 0.1), DVec2::new(1.0, 0.0));
            let mut stats = Stats::default();
            let all: Vec<u32> = (0..scene.walls.len() as u32).collect();
            let bvh = transmittance(&scene, &ray, 100.0, Skip::NONE, None, &mut stats);
            let listed = transmittance(&scene, &ray, 100.0, Skip::NONE, Some(&all), &mut stats);
            let mut expected = Rgb::ONE;
            for wall in &scene.walls[..panes] {
                if let Material::Transparent { tint } = wall.material {
                    expected *= tint;
                }
            }
            assert_eq!(bvh, expected, "{panes} panes, BVH");
            assert_eq!(listed, expected, "{panes} panes, list");
            // An opaque wall across the ray: nothing gets through.
            let blocked = Ray::new(DVec2::new(0.0, 3.2), DVec2::new(0.0, 1.0));
            assert_eq!(
                transmittance(&scene, &blocked, 100.0, Skip::NONE, None, &mut stats),
                Rgb::ZERO
            );
        }
    }
}
