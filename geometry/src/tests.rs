use super::*;

fn v(x: f64, y: f64) -> DVec2 {
    DVec2::new(x, y)
}

fn seg(ax: f64, ay: f64, bx: f64, by: f64) -> Segment {
    Segment::new(v(ax, ay), v(bx, by))
}

#[test]
fn hit_reports_distance_and_segment_parameter() {
    let hit = intersect(
        &Ray::new(v(0.0, 0.0), v(1.0, 0.0)),
        &seg(5.0, -1.0, 5.0, 3.0),
    )
    .unwrap();
    assert_eq!(hit.t, 5.0);
    assert_eq!(hit.u, 0.25);
}

#[test]
fn every_orientation_uses_the_same_formula() {
    // Vertical, horizontal and diagonal walls around the origin, each hit
    // by a ray from the origin at the wall's midpoint.
    for k in 0..360 {
        let angle = (k as f64).to_radians();
        let dir = v(angle.cos(), angle.sin());
        let mid = dir * 10.0;
        let tangent = dir.perp();
        let wall = Segment::new(mid - tangent * 2.0, mid + tangent * 2.0);
        let hit = intersect(&Ray::new(DVec2::ZERO, dir), &wall).unwrap();
        assert!((hit.t - 10.0).abs() < 1e-12, "angle {k}: t = {}", hit.t);
        assert!((hit.u - 0.5).abs() < 1e-12, "angle {k}: u = {}", hit.u);
    }
}

#[test]
fn misses_behind_beside_and_parallel() {
    let wall = seg(5.0, -1.0, 5.0, 1.0);
    // Behind the origin.
    assert!(intersect(&Ray::new(v(0.0, 0.0), v(-1.0, 0.0)), &wall).is_none());
    // Beside the segment.
    assert!(intersect(&Ray::new(v(0.0, 2.0), v(1.0, 0.0)), &wall).is_none());
    // Parallel to it.
    assert!(intersect(&Ray::new(v(0.0, 0.0), v(0.0, 1.0)), &wall).is_none());
}

#[test]
fn collinear_rays_slide_along_and_do_not_hit() {
    let wall = seg(2.0, 0.0, 6.0, 0.0);
    // Along the wall, overlapping it and not.
    assert!(intersect(&Ray::new(v(0.0, 0.0), v(1.0, 0.0)), &wall).is_none());
    assert!(intersect(&Ray::new(v(3.0, 0.0), v(1.0, 0.0)), &wall).is_none());
    assert!(intersect(&Ray::new(v(10.0, 0.0), v(1.0, 0.0)), &wall).is_none());
}

#[test]
fn endpoints_are_hit_exactly() {
    let wall = seg(5.0, 0.0, 5.0, 4.0);
    let at_a = intersect(&Ray::new(v(0.0, 0.0), v(1.0, 0.0)), &wall).unwrap();
    assert_eq!((at_a.t, at_a.u), (5.0, 0.0));
    let at_b = intersect(&Ray::new(v(0.0, 4.0), v(1.0, 0.0)), &wall).unwrap();
    assert_eq!((at_b.t, at_b.u), (5.0, 1.0));
}

#[test]
fn a_ray_through_a_shared_corner_crosses_one_of_the_walls() {
    // Two walls meeting at (1/3, 1/10), a point no binary float holds
    // exactly; rays aimed at it from many directions must cross at least
    // one wall.
    let corner = v(1.0 / 3.0, 0.1);
    let walls = SegmentSet::new(vec![
        Segment::new(v(-2.0, 0.7), corner),
        Segment::new(corner, v(2.3, 0.9)),
    ]);
    for k in 0..1000 {
        let origin = v(0.123 + k as f64 * 1e-3, -3.0 - k as f64 * 7e-4);
        let ray = Ray::new(origin, corner - origin);
        assert!(
            walls.closest_hit(&ray, f64::INFINITY, Skip::NONE).is_some(),
            "ray {k} leaked"
        );
    }
}

#[test]
fn reflection_preserves_length_and_mirrors_the_angle() {
    let wall = seg(0.0, 0.0, 3.0, 4.0);
    let n = wall.normal();
    let d = v(0.3, -2.0);
    let r = reflect(d, n);
    assert!((r.length() - d.length()).abs() < 1e-12);
    assert!((r.dot(n) + d.dot(n)).abs() < 1e-12);
    assert!((r.dot(wall.edge()) - d.dot(wall.edge())).abs() < 1e-12);
}

#[test]
fn sides_and_normals_agree() {
    let wall = seg(0.0, 0.0, 4.0, 0.0);
    let n = wall.normal();
    assert_eq!(wall.side_of(wall.a + n), Some(Side::Positive));
    assert_eq!(wall.side_of(wall.a - n), Some(Side::Negative));
    assert_eq!(wall.side_of(v(7.0, 0.0)), None);
    // A ray travelling against the positive normal arrives from that side.
    assert_eq!(wall.arrival_side(-n), Some(Side::Positive));
    assert_eq!(wall.arrival_side(n), Some(Side::Negative));
    assert_eq!(wall.arrival_side(v(1.0, 0.0)), None);
}

#[test]
fn closest_hit_skips_and_picks_nearest() {
    let walls = SegmentSet::new(vec![
        seg(5.0, -1.0, 5.0, 1.0),
        seg(3.0, -1.0, 3.0, 1.0),
        seg(8.0, -1.0, 8.0, 1.0),
    ]);
    let ray = Ray::new(v(0.0, 0.0), v(1.0, 0.0));
    assert_eq!(
        walls
            .closest_hit(&ray, f64::INFINITY, Skip::NONE)
            .unwrap()
            .0,
        1
    );
    assert_eq!(
        walls
            .closest_hit(&ray, f64::INFINITY, Skip::one(1))
            .unwrap()
            .0,
        0
    );
    assert!(walls.closest_hit(&ray, 2.0, Skip::NONE).is_none());
    let mut seen = Vec::new();
    walls.for_each_crossing(&ray, 6.0, Skip::NONE, |i, _| {
        seen.push(i);
        true
    });
    assert_eq!(seen, vec![0, 1]);
}

#[test]
fn refraction_follows_snell_and_reflects_totally_beyond_the_critical_angle() {
    let n = v(0.0, 1.0);
    for degrees in [0.0f64, 10.0, 30.0, 45.0, 60.0] {
        let a = degrees.to_radians();
        let d = v(a.sin(), -a.cos());
        let t = refract(d, n, 1.0 / 1.5).unwrap();
        assert!((t.length() - 1.0).abs() < 1e-12);
        // n1 sin(i) = n2 sin(t).
        assert!((1.0 * a.sin() - 1.5 * t.x).abs() < 1e-12, "{degrees}");
        assert!(t.y < 0.0, "continues through");
    }
    // From glass to air beyond asin(1 / 1.5) = 41.8 degrees: no refraction.
    let a = 42.0f64.to_radians();
    assert!(refract(v(a.sin(), -a.cos()), n, 1.5).is_none());
    let a = 41.0f64.to_radians();
    assert!(refract(v(a.sin(), -a.cos()), n, 1.5).is_some());
}

/// Closed segments meet when they cross, touch, or overlap on one line;
/// on one line but apart, or parallel apart, they do not.
#[test]
fn segments_meet_when_they_share_a_point() {
    let a = seg(0.0, 0.0, 4.0, 0.0);
    assert!(segments_meet(&a, &seg(2.0, -1.0, 2.0, 1.0)), "crossing");
    assert!(
        segments_meet(&a, &seg(2.0, 0.0, 2.0, 1.0)),
        "touching at an end"
    );
    assert!(
        segments_meet(&a, &seg(4.0, 0.0, 5.0, 3.0)),
        "sharing an end"
    );
    assert!(
        segments_meet(&a, &seg(3.0, 0.0, 6.0, 0.0)),
        "overlapping on one line"
    );
    assert!(segments_meet(&a, &seg(6.0, 0.0, -1.0, 0.0)), "holding it");
    assert!(
        !segments_meet(&a, &seg(5.0, 0.0, 6.0, 0.0)),
        "on one line, apart"
    );
    assert!(!segments_meet(&a, &seg(0.0, 1.0, 4.0, 1.0)), "parallel");
    assert!(
        !segments_meet(&a, &seg(5.0, -1.0, 5.0, 1.0)),
        "beyond its end"
    );
    assert!(!segments_meet(&a, &seg(2.0, 0.5, 3.0, 2.0)), "above it");
    // Either order, and turned.
    for (p, q) in [(a, seg(3.0, 0.0, 6.0, 0.0)), (a, seg(5.0, 0.0, 6.0, 0.0))] {
        assert_eq!(segments_meet(&p, &q), segments_meet(&q, &p));
    }
}
