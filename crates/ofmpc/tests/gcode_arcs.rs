//! Random arcs in every plane, both directions, by R (short and long way) and by I/J/K, with
//! and without helical travel: the reader's arc ends at the programmed point, stays on its
//! circle, turns the programmed way and takes the short or the long way as R's sign says.

use nalgebra::Vector3;
use ofmpc::gcode::{parse, MoveKind, ParseOptions};
use ofmpc::geometry::{Plane, Segment};
use proptest::prelude::*;
use std::f64::consts::PI;

fn plane_of(k: usize) -> (Plane, &'static str, [char; 3], [char; 3]) {
    // (plane, G code, axis letters u v w, offset letters u v w)
    match k % 3 {
        0 => (Plane::XY, "G17", ['X', 'Y', 'Z'], ['I', 'J', 'K']),
        1 => (Plane::ZX, "G18", ['Z', 'X', 'Y'], ['K', 'I', 'J']),
        _ => (Plane::YZ, "G19", ['Y', 'Z', 'X'], ['J', 'K', 'I']),
    }
}

fn only_arc(text: &str) -> Segment {
    let p = parse(text, &ParseOptions::default()).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_eq!(p.moves.len(), 1, "{text}");
    match &p.moves[0].kind {
        MoveKind::Path { segment, .. } => segment.clone(),
        MoveKind::Dwell { .. } => panic!("dwell"),
    }
}

/// Point from in-plane (u, v) and normal w coordinates (m).
fn point(plane: Plane, u: f64, v: f64, w: f64) -> Vector3<f64> {
    let (iu, iv, iw) = plane.axes();
    let mut p = Vector3::zeros();
    p[iu] = u;
    p[iv] = v;
    p[iw] = w;
    p
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn r_arcs(
        k in 0usize..3,
        (su, sv) in (-500i32..500, -500i32..500),
        (eu, ev) in (-500i32..500, -500i32..500),
        extra in 0.0f64..300.0,
        long in any::<bool>(),
        ccw in any::<bool>(),
        helix in -50i32..50,
    ) {
        let (plane, g, ax, _) = plane_of(k);
        let chord = f64::from(eu - su).hypot(f64::from(ev - sv));
        prop_assume!(chord > 1.0);
        let r = chord / 2.0 + extra + 1e-3;
        let r_text = if long { -r } else { r };
        let text = format!(
            "{g} G0 {}{su} {}{sv} {}0\n{} {}{eu} {}{ev} {}{helix} R{r_text:.9}\n",
            ax[0], ax[1], ax[2], if ccw { "G3" } else { "G2" }, ax[0], ax[1], ax[2]
        );
        let seg = only_arc(&text);
        let target = point(plane, f64::from(eu) * 1e-3, f64::from(ev) * 1e-3, f64::from(helix) * 1e-3);
        prop_assert!((seg.end() - target).norm() < 1e-12, "{} vs {}", seg.end(), target);
        let Segment::Arc { center, radius, sweep, .. } = seg.clone() else { panic!() };
        prop_assert!((radius - r * 1e-3).abs() < 1e-12);
        prop_assert_eq!(sweep > 0.0, ccw);
        if long {
            prop_assert!(sweep.abs() >= PI - 1e-9);
        } else {
            prop_assert!(sweep.abs() <= PI + 1e-9);
        }
        let (iu, iv, _) = plane.axes();
        for i in 0..=20 {
            let p = seg.point(seg.length() * f64::from(i) / 20.0);
            let d = (p[iu] - center[iu]).hypot(p[iv] - center[iv]);
            prop_assert!((d - radius).abs() < 1e-12);
        }
    }

    #[test]
    fn ijk_arcs(
        k in 0usize..3,
        (cu, cv) in (-300i32..300, -300i32..300),
        r in 1.0f64..400.0,
        (a0, a1) in (0.0f64..(2.0 * PI), 0.0f64..(2.0 * PI)),
        ccw in any::<bool>(),
        helix in -50i32..50,
    ) {
        let (plane, g, ax, off) = plane_of(k);
        let (cu, cv) = (f64::from(cu), f64::from(cv));
        let (su, sv) = (cu + r * a0.cos(), cv + r * a0.sin());
        let (eu, ev) = (cu + r * a1.cos(), cv + r * a1.sin());
        // Coordinates written with 6 decimals (1 nm): far inside the 0.002 mm tolerance.
        let text = format!(
            "{g} G0 {}{su:.6} {}{sv:.6} {}0\n{} {}{eu:.6} {}{ev:.6} {}{helix} {}{:.6} {}{:.6}\n",
            ax[0], ax[1], ax[2], if ccw { "G3" } else { "G2" }, ax[0], ax[1], ax[2],
            off[0], cu - su, off[1], cv - sv
        );
        let seg = only_arc(&text);
        let Segment::Arc { center, radius, sweep, .. } = seg.clone() else { panic!() };
        prop_assert!((radius - r * 1e-3).abs() < 2e-9);
        prop_assert!((center - point(plane, cu * 1e-3, cv * 1e-3, 0.0)).norm() < 2e-9);
        prop_assert_eq!(sweep > 0.0, ccw);
        // The sweep is the programmed angle, the long or short way as the direction says.
        let ccw_angle = (a1 - a0).rem_euclid(2.0 * PI);
        let expect = if ccw { ccw_angle } else { ccw_angle - 2.0 * PI };
        let wrapped = (sweep - expect).rem_euclid(2.0 * PI);
        prop_assert!(wrapped.min(2.0 * PI - wrapped) < 1e-6, "sweep {sweep} expected {expect}");
        let target = point(plane, eu * 1e-3, ev * 1e-3, f64::from(helix) * 1e-3);
        prop_assert!((seg.end() - target).norm() < 2e-9);
        let t = seg.tangent(0.5 * seg.length());
        prop_assert!((t.norm() - 1.0).abs() < 1e-12);
    }
}
