//! G64 corners at CNC speed (issue 38 item 4): a 200 mm square at F12000 with `G64 P0.5`
//! passes each 90° corner at F/10 or faster, within the tolerance, and is never slower than
//! the same program under `G61`. Until issue 38 the timing traded every blend slower than
//! about 80 mm/s at this feed for an exact stop (`blend_timed`), so the square stopped at
//! each corner.

use nalgebra::Vector3;
use ofmpc::motion::{plan, CartesianTrajectory, PlanOptions};
use ofmpc::robot::Robot;

/// The square of 200 mm sides around (500, 0, 400) mm at F12000 (0.2 m/s) under `mode`.
fn square(mode: &str) -> String {
    format!("G21 G90 {mode}\nG0 X400 Y-100 Z400\nG1 X600 F12000\nY100\nX400\nY-100\n")
}

fn corners() -> Vec<Vector3<f64>> {
    [
        (400.0, -100.0),
        (600.0, -100.0),
        (600.0, 100.0),
        (400.0, 100.0),
        (400.0, -100.0),
    ]
    .iter()
    .map(|&(x, y)| Vector3::new(x, y, 400.0) * 1e-3)
    .collect()
}

/// The trajectory's samples every 0.1 ms.
fn samples(tr: &CartesianTrajectory) -> impl Iterator<Item = (Vector3<f64>, f64)> + '_ {
    let n = (tr.duration() / 1e-4).ceil() as usize;
    (0..=n).map(move |k| {
        let s = tr.sample(k as f64 * 1e-4);
        (s.position, s.velocity.norm())
    })
}

fn dist_to_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    let u = b - a;
    let t = ((p - a).dot(&u) / u.norm_squared()).clamp(0.0, 1.0);
    (p - (a + u * t)).norm()
}

#[test]
fn square_corners_at_f12000_p05_blend_at_a_tenth_of_the_feed_or_faster() {
    let robot = Robot::irb140();
    let opts = PlanOptions::default();
    let g64 = plan(&square("G64 P0.5"), &robot, &opts).unwrap();
    let g61 = plan(&square("G61"), &robot, &opts).unwrap();
    let c = corners();
    let feed = 0.2;
    // The slowest sample within 5 mm of each interior corner.
    for corner in &c[1..4] {
        let slowest = samples(&g64.trajectory)
            .filter(|(p, _)| (p - corner).norm() < 5e-3)
            .map(|(_, v)| v)
            .fold(f64::INFINITY, f64::min);
        assert!(
            slowest >= feed / 10.0,
            "corner {:?} passed at {:.2} mm/s, below F/10",
            corner * 1e3,
            slowest * 1e3
        );
        eprintln!("corner {:?}: {:.2} mm/s", corner * 1e3, slowest * 1e3);
    }
    let deviation = samples(&g64.trajectory)
        .map(|(p, _)| {
            c.windows(2)
                .map(|w| dist_to_segment(p, w[0], w[1]))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0, f64::max);
    assert!(deviation <= 0.5e-3, "deviation {} mm", deviation * 1e3);
    let (d64, d61) = (g64.diagnostics.duration, g61.diagnostics.duration);
    assert!(d64 <= d61, "G64 {d64} s slower than G61 {d61} s");
    // A lower bound of the time-optimal timing without a jerk limit: the length at the feed
    // and the speed-up and slow-down at the path acceleration (2.5 m/s²), corners ignored.
    let bound = 0.8 / feed + feed / 2.5;
    eprintln!(
        "square F12000 P0.5: G64 {d64:.3} s (deviation {:.3} mm), G61 {d61:.3} s, \
         lower bound {bound:.3} s, ratio {:.3}",
        deviation * 1e3,
        d64 / bound
    );
    assert!(d64 >= bound, "{d64} s beats the lower bound {bound} s");
    // Measured 1.254 (5.118 s) with the filter window 2a/j over the whole run, which held each
    // corner's speed over ±1.1 T_j v around its blend; 1.153 (4.703 s; TOPP-RA's optimum
    // without a jerk limit is 4.217 s, the Python timing test's bound 4.739 s) with the window
    // a/j, the erosion of half a window and a finer grid on the lines next to the blends
    // (`timing/topp.rs`: `choose_windows`, `near_blend_step`).
    assert!(d64 <= 1.16 * bound, "{d64} s against the bound {bound} s");
}

/// The square's speed changes (filtered over `a/j` since issue 38) keep the jerk setting: the
/// path jerk `|Δa| / Δt` over 1 ms samples stays within 50 m/s³ (5 % for the sampling) where
/// the path is straight (farther than 3 mm from every corner, outside the blends), and within
/// twice it everywhere (issue 26's bound, `tests/motion_jerk.rs`).
#[test]
fn the_squares_speed_changes_keep_the_jerk_setting() {
    let robot = Robot::irb140();
    let opts = PlanOptions::default();
    let jerk = opts.timing.max_jerk;
    let tr = plan(&square("G64 P0.5"), &robot, &opts).unwrap().trajectory;
    let c = corners();
    let h = 1e-3;
    let n = (tr.duration() / h).ceil() as usize;
    let mut prev = tr.sample(0.0).acceleration;
    let (mut straight, mut anywhere) = (0.0f64, 0.0f64);
    for k in 1..=n {
        let s = tr.sample(k as f64 * h);
        let j = (s.acceleration - prev).norm() / h;
        prev = s.acceleration;
        anywhere = anywhere.max(j);
        if c.iter().all(|p| (s.position - p).norm() > 3e-3) {
            straight = straight.max(j);
        }
    }
    eprintln!("square jerk: {straight:.1} m/s³ on the lines, {anywhere:.1} m/s³ anywhere");
    assert!(straight <= 1.05 * jerk, "{straight} m/s³ on the lines");
    assert!(anywhere <= 2.0 * jerk, "{anywhere} m/s³");
}
