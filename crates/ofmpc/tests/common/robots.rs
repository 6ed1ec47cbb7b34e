//! Shared helpers of the integration tests: a deterministic RNG and random robots.
#![allow(dead_code)]

use ofmpc::robot::Robot;

pub use super::rng;

/// A small deterministic generator (the tests' one LCG), so tests are reproducible.
pub use rng::Lcg as Rng;

/// A random serial chain as URDF text: revolute and prismatic joints with
/// random origins, axes and inertials, and fixed joints in between.
pub fn random_urdf(rng: &mut Rng, n: usize, with_prismatic: bool) -> String {
    let mut s = String::from("<robot name=\"random\">\n<link name=\"base\"/>\n");
    let mut parent = "base".to_string();
    for i in 0..n {
        let child = format!("l{i}");
        let kind = if with_prismatic && i % 3 == 1 {
            "prismatic"
        } else {
            "revolute"
        };
        let ax = [
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        ];
        s += &format!(
            "<joint name=\"j{i}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
             <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/><axis xyz=\"{} {} {}\"/>\
             <limit lower=\"-3\" upper=\"3\" velocity=\"2\" effort=\"100\"/></joint>\n",
            rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), rng.range(0.0, 0.4),
            rng.range(-3.0, 3.0), rng.range(-1.5, 1.5), rng.range(-3.0, 3.0),
            ax[0], ax[1], ax[2]
        );
        // Principal moments satisfying the triangle inequality, rotated by rpy.
        let (a, b) = (rng.range(0.01, 0.1), rng.range(0.01, 0.1));
        let c = rng.range((a - b).abs() + 0.001, a + b);
        s += &format!(
            "<link name=\"{child}\"><inertial><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/><mass value=\"{}\"/>\
             <inertia ixx=\"{a}\" ixy=\"0\" ixz=\"0\" iyy=\"{b}\" iyz=\"0\" izz=\"{c}\"/></inertial></link>\n",
            rng.range(-0.1, 0.1), rng.range(-0.1, 0.1), rng.range(-0.1, 0.1),
            rng.range(-3.0, 3.0), rng.range(-1.5, 1.5), rng.range(-3.0, 3.0),
            rng.range(0.5, 5.0)
        );
        parent = child;
        if i % 2 == 0 {
            // A fixed intermediate frame with mass, folded into the body.
            let fixed = format!("f{i}");
            s += &format!(
                "<joint name=\"fx{i}\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"{fixed}\"/>\
                 <origin xyz=\"0.05 0.02 0.1\" rpy=\"0.1 0.2 0.3\"/></joint>\n\
                 <link name=\"{fixed}\"><inertial><origin xyz=\"0.01 0 0\"/><mass value=\"0.3\"/>\
                 <inertia ixx=\"0.001\" ixy=\"0\" ixz=\"0\" iyy=\"0.001\" iyz=\"0\" izz=\"0.001\"/></inertial></link>\n"
            );
            parent = fixed;
        }
    }
    s += &format!(
        "<joint name=\"tool\" type=\"fixed\"><parent link=\"{parent}\"/><child link=\"tool0\"/>\
         <origin xyz=\"0 0 0.1\" rpy=\"0 1.5707963267948966 0\"/></joint>\n<link name=\"tool0\"/>\n</robot>\n"
    );
    s
}

/// Random robots for property tests: the IRB 140, and random chains.
pub fn robots(rng: &mut Rng) -> Vec<(String, Robot)> {
    let mut v = vec![("irb140".to_string(), Robot::irb140())];
    let mut bare = Robot::irb140();
    // Without armature the wrist is nearly singular: a harder numerical case.
    let text = ofmpc::robot::IRB140_URDF;
    bare = Robot::from_urdf_str(text).unwrap_or(bare);
    v.push(("irb140-no-armature".to_string(), bare));
    for (n, pris) in [(3, false), (6, true), (7, true)] {
        let urdf = random_urdf(rng, n, pris);
        v.push((
            format!("random{n}"),
            Robot::from_urdf_str(&urdf).expect("random URDF is valid"),
        ));
    }
    v
}

/// Test poses P0..P6 of PARAMETERS.md (the IRB 140): q, flange position,
/// flange rotation rows, as printed there (9 decimals).
#[allow(clippy::type_complexity, clippy::approx_constant)]
pub fn parameter_poses() -> Vec<([f64; 6], [f64; 3], [f64; 9])> {
    let d = |x: f64| x.to_radians();
    vec![
        (
            [0.0; 6],
            [0.515, 0.0, 0.712],
            [0., 0., 1., 0., 1., 0., -1., 0., 0.],
        ),
        (
            [d(90.0), 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.515, 0.712],
            [0., -1., 0., 0., 0., 1., -1., 0., 0.],
        ),
        (
            [0.0, d(30.0), 0.0, 0.0, 0.0, 0.0],
            [0.635381305, 0.0, 0.441269145],
            [-0.5, 0., 0.866025404, 0., 1., 0., -0.866025404, 0., -0.5],
        ),
        (
            [0.0, 0.0, d(-90.0), 0.0, 0.0, 0.0],
            [0.070, 0.0, 1.157],
            [1., 0., 0., 0., 1., 0., 0., 0., 1.],
        ),
        (
            [0.0, 0.0, 0.0, 0.0, d(90.0), 0.0],
            [0.450, 0.0, 0.647],
            [-1., 0., 0., 0., 1., 0., 0., 0., -1.],
        ),
        (
            [0.0, 0.0, 0.0, d(90.0), d(45.0), d(30.0)],
            [0.495961941, 0.045961941, 0.712],
            [
                -0.612372436,
                0.353553391,
                0.707106781,
                0.612372436,
                -0.353553391,
                0.707106781,
                0.5,
                0.866025404,
                0.0,
            ],
        ),
        (
            [0.3, -0.4, 0.5, 1.0, -0.6, 2.0],
            [0.356171283, 0.077849371, 0.660020493],
            [
                -0.192462260,
                -0.229702739,
                0.954041367,
                0.152204704,
                -0.967439544,
                -0.202223780,
                0.969428701,
                0.106289138,
                0.221157439,
            ],
        ),
    ]
}
