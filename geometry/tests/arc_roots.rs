//! Arcs against an exact reference: every root the arc rule reports is
//! within a stated distance of a true root of the stored circle (its
//! sign change evaluated in exact rational arithmetic), every true
//! crossing clearly inside the arc is reported, rays that leave an arc
//! meet it again exactly where they should, and rooms of arcs and
//! segments sharing ends let no ray out. Fixed proptest seeds.

use flatray_geometry::{
    Arc, DVec2, Ray, Segment, SegmentSet, Shape, Skip, Strategy as Accel, arc_crossings, cross,
};
use num_rational::BigRational;
use num_traits::{Signed, Zero};
use proptest::prelude::*;

fn q(x: f64) -> BigRational {
    BigRational::from_float(x).unwrap_or_else(BigRational::zero)
}

/// The sign of `|o + t d - c|^2 - r^2`, exactly, for the arc's stored
/// centre and radius.
fn circle_sign(arc: &Arc, ray: &Ray, t: f64) -> i32 {
    let t = q(t);
    let x = q(ray.origin.x) + &t * q(ray.dir.x) - q(arc.center.x);
    let y = q(ray.origin.y) + &t * q(ray.dir.y) - q(arc.center.y);
    let g = &x * &x + &y * &y - q(arc.radius) * q(arc.radius);
    if g.is_positive() {
        1
    } else if g.is_negative() {
        -1
    } else {
        0
    }
}

/// Whether a true root of the circle lies within `delta` of `t`: the
/// exact sign changes (or vanishes) across `[t - delta, t + delta]`, or
/// the line touches the circle there (a tangent: the sign at the nearest
/// approach is not that of the ends).
fn root_near(arc: &Arc, ray: &Ray, t: f64, delta: f64) -> bool {
    let (lo, mid, hi) = (
        circle_sign(arc, ray, t - delta),
        circle_sign(arc, ray, t),
        circle_sign(arc, ray, t + delta),
    );
    lo == 0 || mid == 0 || hi == 0 || lo != hi || lo != mid
}

/// The exact roots' approximate values, from the reference side: the
/// foot of the perpendicular and the half chord in f64, for locating.
fn approximate_roots(arc: &Arc, ray: &Ray) -> Option<(f64, f64)> {
    let f = ray.origin - arc.center;
    let dd = ray.dir.dot(ray.dir);
    let mid = -f.dot(ray.dir) / dd;
    let foot = f + mid * ray.dir;
    let h2 = arc.radius * arc.radius - foot.length_squared();
    (h2 > 0.0).then(|| {
        let s = (h2 / dd).sqrt();
        (mid - s, mid + s)
    })
}

/// How far along the arc's side of its chord `p` lies, exactly; +inf for
/// a full circle.
fn margin_exact(arc: &Arc, p: DVec2) -> f64 {
    if arc.is_full() {
        return f64::INFINITY;
    }
    arc.bulge * cross(arc.b - arc.a, p - arc.a)
}

fn scale() -> impl Strategy<Value = f64> {
    prop_oneof![Just(1e-3), Just(1.0), Just(1e3), Just(1e6)]
}

fn arc_and_ray() -> impl Strategy<Value = (Arc, Ray, f64)> {
    (
        scale(),
        (-2.0..2.0f64, -2.0..2.0f64),
        0.2..3.0f64,
        0.0..std::f64::consts::TAU,
        prop_oneof![0.05..6.2f64, Just(std::f64::consts::PI), Just(7.0)],
        any::<bool>(),
        (-5.0..5.0f64, -5.0..5.0f64),
        prop_oneof![Just(1.0), Just(1e3), Just(1e5)],
        0.0..std::f64::consts::TAU,
    )
        .prop_map(|(s, (cx, cy), r, from, span, cw, (ox, oy), far, angle)| {
            // Far from the origin of coordinates at the larger scales.
            let centre = DVec2::new(cx, cy) * s + DVec2::splat(3.0 * s);
            let span = if cw { -span } else { span };
            let arc = Arc::from_angles(centre, r * s, from, from + span).expect("an arc");
            // From near the arc, or from far away (where `r^2 - |f|^2`
            // written plainly loses every digit), aimed near the centre.
            let origin = centre + DVec2::new(ox, oy) * s * far;
            let aim = if far > 1.0 {
                centre - origin
            } else {
                DVec2::new(angle.cos(), angle.sin())
            };
            let turn = (angle - std::f64::consts::PI) * 1e-3 / far;
            let (sn, cs) = turn.sin_cos();
            let dir = aim.normalize();
            let dir = DVec2::new(dir.x * cs - dir.y * sn, dir.x * sn + dir.y * cs);
            let ray = Ray::new(origin, dir);
            (arc, ray, s)
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, rng_seed: proptest::test_runner::RngSeed::Fixed(29), ..ProptestConfig::default() })]

    /// Each reported root is within 1e-12 of the arc's size of a true
    /// root, lies on the arc's side of its chord to within that, and every
    /// true crossing clearly inside the arc (and clearly ahead) is found.
    #[test]
    fn crossings_match_the_exact_circle((arc, ray, s) in arc_and_ray()) {
        // A few units in the last place of the root's distance.
        let exact = |t: f64| 16.0 * f64::EPSILON * (t.abs() + s);
        let delta = 1e-12 * s * 8.0;
        let (hits, n) = arc_crossings(&ray, &arc, f64::INFINITY, false, false);
        for hit in &hits[..n] {
            prop_assert!(hit.t > 0.0);
            prop_assert!(root_near(&arc, &ray, hit.t, exact(hit.t)), "t = {} is no root", hit.t);
            prop_assert!(margin_exact(&arc, ray.at(hit.t)) > -delta * s * 4.0);
            prop_assert!((0.0..=1.0).contains(&hit.u));
            let back = arc.point_at(hit.u);
            prop_assert!((back - ray.at(hit.t)).length() < 1e-9 * (s + hit.t), "u = {} is off", hit.u);
        }
        if let Some((t1, t2)) = approximate_roots(&arc, &ray) {
            for t in [t1, t2] {
                let p = ray.at(t);
                let inside = margin_exact(&arc, p) > 1e-9 * s * s;
                let tangent = (t2 - t1).abs() < 1e-6 * s;
                if inside && t > 1e-9 * s && !tangent {
                    prop_assert!(
                        hits[..n].iter().any(|h| (h.t - t).abs() < 1e-9 * (s + t.abs())),
                        "missed the root at t = {t}"
                    );
                }
            }
        }
    }

    /// A ray that starts on an arc, skipping it, meets it again exactly at
    /// the circle's other root, and only where that root is on the arc; it
    /// never meets its own origin.
    #[test]
    fn a_ray_leaving_an_arc_meets_it_again_only_where_it_should(
        (arc, ray, s) in arc_and_ray(),
        u in 0.01..0.99f64,
    ) {
        let origin = arc.point_at(u);
        let ray = Ray::new(origin, ray.dir);
        let (hits, n) = arc_crossings(&ray, &arc, f64::INFINITY, true, false);
        prop_assert!(n <= 1);
        let other = -2.0 * (origin - arc.center).dot(ray.dir) / ray.dir.dot(ray.dir);
        if n == 1 {
            prop_assert!(hits[0].t > 0.0);
            prop_assert!((hits[0].t - other).abs() <= 1e-12 * s.max(other.abs()) * 4.0);
            prop_assert!(margin_exact(&arc, ray.at(hits[0].t)) > -1e-9 * s * s);
        } else if other > 1e-9 * s {
            // Not met again: the other root lies off the arc.
            prop_assert!(margin_exact(&arc, ray.at(other)) < 1e-9 * s * s);
        }
        // Without the skip, the origin itself may be found, but never
        // anything the skipped query missed beyond it.
        let (all, m) = arc_crossings(&ray, &arc, f64::INFINITY, false, false);
        for h in &all[..m] {
            if h.t > 1e-9 * s {
                prop_assert!(n == 1 && (h.t - hits[0].t).abs() < 1e-9 * s);
            }
        }
    }
}

#[test]
fn tangent_and_grazing_rays() {
    let c = DVec2::new(10.0, -4.0);
    let circle = Arc::circle(c, 2.0, 0.3);
    // Tangent to the full circle: it passes.
    let tangent = Ray::new(c + DVec2::new(-5.0, 2.0), DVec2::X);
    assert_eq!(
        arc_crossings(&tangent, &circle, f64::INFINITY, false, false).1,
        0
    );
    // Just inside the tangent: two crossings, close together.
    let grazing = Ray::new(c + DVec2::new(-5.0, 2.0 - 1e-9), DVec2::X);
    let (hits, n) = arc_crossings(&grazing, &circle, f64::INFINITY, false, false);
    assert_eq!(n, 2);
    assert!((hits[1].t - hits[0].t).abs() < 1e-3 && hits[0].t < hits[1].t);
    // A ray leaving the circle along its tangent meets nothing.
    let along = Ray::new(c + DVec2::new(0.0, 2.0), DVec2::X);
    assert_eq!(
        arc_crossings(&along, &circle, f64::INFINITY, true, false).1,
        0
    );
    // A half circle (ends on the x axis through the centre, bulging up):
    // a ray along its chord's line touches only its ends, and passes.
    let half = Arc::through(c - DVec2::X * 2.0, c + DVec2::Y * 2.0, c + DVec2::X * 2.0).unwrap();
    let chord = Ray::new(c - DVec2::X * 5.0, DVec2::X);
    assert_eq!(
        arc_crossings(&chord, &half, f64::INFINITY, false, false).1,
        0
    );
    // Just above the chord: one crossing at each side of the half circle.
    let above = Ray::new(c + DVec2::new(-5.0, 1e-12), DVec2::X);
    assert_eq!(
        arc_crossings(&above, &half, f64::INFINITY, false, false).1,
        2
    );
    // Just below: none.
    let below = Ray::new(c + DVec2::new(-5.0, -1e-12), DVec2::X);
    assert_eq!(
        arc_crossings(&below, &half, f64::INFINITY, false, false).1,
        0
    );
}

#[test]
fn three_points_keep_the_ends_and_turn_through_the_middle() {
    let (a, m, b) = (
        DVec2::new(1.0, 0.0),
        DVec2::new(0.0, 1.0),
        DVec2::new(-1.0, 0.0),
    );
    let arc = Arc::through(a, m, b).unwrap();
    assert_eq!((arc.a, arc.b), (a, b));
    assert!((arc.center - DVec2::ZERO).length() < 1e-15);
    assert!((arc.radius - 1.0).abs() < 1e-15);
    assert!((arc.sweep - std::f64::consts::PI).abs() < 1e-15);
    assert!((arc.point_at(0.5) - m).length() < 1e-15);
    // The other way round: clockwise, through the bottom.
    let other = Arc::through(a, DVec2::new(0.0, -1.0), b).unwrap();
    assert!((other.point_at(0.5) - DVec2::new(0.0, -1.0)).length() < 1e-15);
    assert_eq!(arc.turn, -other.turn);
    // A major arc: three quarters of the circle.
    let major = Arc::through(a, DVec2::new(-1.0, 0.0), DVec2::new(0.0, -1.0)).unwrap();
    assert!((major.sweep - 1.5 * std::f64::consts::PI).abs() < 1e-14);
    assert!((major.length() - 1.5 * std::f64::consts::PI).abs() < 1e-14);
    let (lo, hi) = major.bounds();
    assert!((lo - DVec2::splat(-1.0)).length() < 1e-15);
    assert!((hi - DVec2::splat(1.0)).length() < 1e-15);
    assert!(Arc::through(a, DVec2::new(3.0, 0.0), DVec2::new(5.0, 0.0)).is_err());
    assert!(Arc::through(a, a, b).is_err());
}

/// A closed room of arcs and segments sharing their ends (exactly), turned
/// by `angle` about `centre`: a polygon whose every other edge bulges in
/// or out.
fn mixed_room(centre: DVec2, radius: f64, sides: usize, angle: f64, bulges: &[f64]) -> Vec<Shape> {
    let corner = |k: usize| {
        let a = angle + std::f64::consts::TAU * k as f64 / sides as f64;
        centre + radius * DVec2::new(a.cos(), a.sin())
    };
    (0..sides)
        .map(|k| {
            let (p, q) = (corner(k), corner((k + 1) % sides));
            let bulge = bulges[k % bulges.len()];
            if bulge == 0.0 {
                Shape::Segment(Segment::new(p, q))
            } else {
                // Through a point off the chord's middle: out (positive)
                // or in (negative).
                let mid = (p + q) * 0.5;
                let out = (mid - centre).normalize();
                Shape::Arc(Arc::through(p, mid + out * bulge * (q - p).length(), q).unwrap())
            }
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, rng_seed: proptest::test_runner::RngSeed::Fixed(31), ..ProptestConfig::default() })]

    /// No ray from inside a closed room of arcs and segments gets out: aimed
    /// at the shared ends from anywhere inside, at any rotation, with the
    /// BVH and brute force alike (which give the same hits).
    #[test]
    fn rooms_of_arcs_and_segments_let_no_ray_out(
        sides in 3usize..9,
        angle in 0.0..std::f64::consts::TAU,
        bulges in proptest::collection::vec(prop_oneof![Just(0.0), -0.15..-0.05f64, 0.05..0.6f64], 1..4),
        (ox, oy) in (-0.1..0.1f64, -0.1..0.1f64),
        s in scale(),
    ) {
        let centre = DVec2::new(1.0 / 3.0, 0.1) * s;
        let shapes = mixed_room(centre, s, sides, angle, &bulges);
        let brute = SegmentSet::shapes_with_strategy(shapes.clone(), Accel::BruteForce);
        let bvh = SegmentSet::shapes_with_strategy(shapes.clone(), Accel::Bvh);
        let origin = centre + DVec2::new(ox, oy) * s;
        let mut aims: Vec<DVec2> = shapes.iter().map(|sh| sh.a()).collect();
        aims.extend(shapes.iter().map(|sh| sh.point_at(0.5)));
        for k in 0..64 {
            let a = k as f64 * 0.0981747704;
            aims.push(origin + DVec2::new(a.cos(), a.sin()));
        }
        for aim in aims {
            let ray = Ray::new(origin, aim - origin);
            let hit = brute.closest_hit(&ray, f64::INFINITY, Skip::NONE);
            prop_assert!(hit.is_some(), "a ray got out towards {aim:?}");
            prop_assert_eq!(hit, bvh.closest_hit(&ray, f64::INFINITY, Skip::NONE));
            // And leaving the wall it met, inwards, it meets another (or
            // the same arc again).
            let (index, h) = hit.unwrap();
            let shape = brute.shape(index);
            let p = shape.point_at(h.u);
            let back = Ray::new(p, origin - p);
            prop_assert!(brute.closest_hit(&back, f64::INFINITY, Skip::one(index)).is_some());
        }
    }
}

#[test]
fn a_round_room_returns_every_ray_to_its_wall() {
    // A full circle far from the origin of coordinates: rays leaving it
    // inwards, skipping it, meet it again at the chord's other end.
    let c = DVec2::new(1e5 + 1.0 / 3.0, -2e5);
    let room = SegmentSet::of_shapes(vec![Shape::Arc(Arc::circle(c, 7.0, 0.1))]);
    for k in 0..720 {
        let a = k as f64 * 0.0087266;
        let start = c + 7.0 * DVec2::new(a.cos(), a.sin());
        let d = DVec2::new((a * 3.7).cos(), (a * 3.7).sin());
        let inward = if d.dot(start - c) < 0.0 { d } else { -d };
        let (index, hit) = room
            .closest_hit(&Ray::new(start, inward), f64::INFINITY, Skip::one(0))
            .expect("the far side");
        assert_eq!(index, 0);
        let p = start + hit.t * inward;
        assert!(((p - c).length() - 7.0).abs() < 1e-9, "{k}: {p:?}");
        // Outwards, nothing.
        assert!(
            room.closest_hit(&Ray::new(start, -inward), f64::INFINITY, Skip::one(0))
                .is_none()
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 60, rng_seed: proptest::test_runner::RngSeed::Fixed(37), ..ProptestConfig::default() })]

    /// A BVH over segments and arcs together answers as brute force does:
    /// hundreds of random arcs (full circles among them) and segments,
    /// closest hits and every crossing (as sets), from rays anywhere and
    /// from rays that leave an arc.
    #[test]
    fn the_bvh_over_arcs_and_segments_answers_as_brute_force(
        shapes in proptest::collection::vec(
            (
                (-100.0..100.0f64, -100.0..100.0f64),
                0.5..20.0f64,
                0.0..std::f64::consts::TAU,
                prop_oneof![0.1..6.0f64, Just(7.0)],
                any::<bool>(),
            ),
            40..300,
        ),
        rays in proptest::collection::vec(((-120.0..120.0f64, -120.0..120.0f64), 0.0..std::f64::consts::TAU), 20),
    ) {
        let shapes: Vec<Shape> = shapes
            .into_iter()
            .map(|((x, y), r, from, span, straight)| {
                let c = DVec2::new(x, y);
                if straight {
                    Shape::Segment(Segment::new(c, c + r * DVec2::new(from.cos(), from.sin())))
                } else {
                    Shape::Arc(Arc::from_angles(c, r, from, from + span).expect("an arc"))
                }
            })
            .collect();
        let brute = SegmentSet::shapes_with_strategy(shapes.clone(), Accel::BruteForce);
        let bvh = SegmentSet::shapes_with_strategy(shapes.clone(), Accel::Bvh);
        let arcs: Vec<u32> = (0..shapes.len() as u32).filter(|&i| shapes[i as usize].as_arc().is_some()).collect();
        for (k, ((ox, oy), a)) in rays.into_iter().enumerate() {
            let dir = DVec2::new(a.cos(), a.sin());
            // From anywhere, and leaving an arc.
            let (origin, skip) = if k % 2 == 0 || arcs.is_empty() {
                (DVec2::new(ox, oy), Skip::NONE)
            } else {
                let i = arcs[k % arcs.len()];
                (shapes[i as usize].point_at(0.37), Skip::one(i))
            };
            let ray = Ray::new(origin, dir);
            prop_assert_eq!(
                brute.closest_hit(&ray, f64::INFINITY, skip),
                bvh.closest_hit(&ray, f64::INFINITY, skip)
            );
            let all = |set: &SegmentSet| {
                let mut v = Vec::new();
                set.for_each_crossing(&ray, 150.0, skip, |i, h| {
                    v.push((i, h.t.to_bits()));
                    true
                });
                v.sort_unstable();
                v
            };
            prop_assert_eq!(all(&brute), all(&bvh));
            // Boxes: the same indices.
            let (lo, hi) = (origin - DVec2::splat(30.0), origin + DVec2::splat(30.0));
            let in_box = |set: &SegmentSet| {
                let (mut v, mut scratch) = (Vec::new(), Vec::new());
                set.for_each_in_box(lo, hi, &mut scratch, |i| v.push(i));
                v
            };
            let (b, t) = (in_box(&brute), in_box(&bvh));
            // Brute force lists everything; the tree, what its boxes meet,
            // which must hold every shape that meets the box.
            for i in &t {
                prop_assert!(b.contains(i));
            }
            for (i, shape) in shapes.iter().enumerate() {
                let (slo, shi) = shape.bounds();
                let meets = slo.x <= hi.x && slo.y <= hi.y && shi.x >= lo.x && shi.y >= lo.y;
                if meets {
                    prop_assert!(t.contains(&(i as u32)), "shape {i} meets the box but is not listed");
                }
            }
        }
    }
}
