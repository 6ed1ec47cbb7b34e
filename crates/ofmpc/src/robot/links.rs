//! Where each link of a URDF sits on the chain (issue #25 item 4: the report draws each
//! link's `<visual>` meshes on the body that carries it).
//!
//! The URDF reader folds fixed joints (and moving joints off the chain, held rigid) into the
//! bodies of the moving joints; a link is then rigidly attached to one body — the base or the
//! body that a moving joint moves — at a constant pose in that body's frame. That pose is the
//! product of the joint origins from the body's frame down to the link (URDF specification,
//! `<joint><origin>`: the child link's frame in the parent link's frame).

use crate::spatial::Transform;

/// A URDF link and the body it is rigidly attached to.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkFrame {
    /// The link's name (`<link name>`).
    pub name: String,
    /// The body that carries it: `None` for the base (the root link's frame), `Some(i)` for
    /// the body moved by joint `i` ([`super::Robot::joints`], base to tip).
    pub body: Option<usize>,
    /// The link's frame in that body's frame (the joint frame after joint `i`'s motion).
    pub pose: Transform,
}

#[cfg(test)]
mod tests {
    use crate::robot::Robot;

    /// The IRB 140: every link on its body, the flange (a fixed frame of link_6) turned by
    /// its joint's rpy; a fixed side link of a middle body composes both fixed origins.
    #[test]
    fn links_sit_on_their_bodies() {
        let r = Robot::irb140();
        let names: Vec<(&str, Option<usize>)> = r
            .link_frames()
            .iter()
            .map(|f| (f.name.as_str(), f.body))
            .collect();
        assert_eq!(
            names,
            [
                ("base_link", None),
                ("link_1", Some(0)),
                ("link_2", Some(1)),
                ("link_3", Some(2)),
                ("link_4", Some(3)),
                ("link_5", Some(4)),
                ("link_6", Some(5)),
                ("flange", Some(5)),
            ]
        );
        let flange = &r.link_frames()[7].pose;
        assert!((flange.rot - r.flange_offset().rot).abs().max() < 1e-15);
        assert!(r.link_frames()[3].pose.pos.norm() == 0.0);
        let text = crate::robot::IRB140_URDF.replace(
            "</robot>",
            "<link name=\"cam\"/><link name=\"lens\"/>\
             <joint name=\"j_cam\" type=\"fixed\"><parent link=\"link_2\"/><child link=\"cam\"/>\
             <origin xyz=\"0.1 0 0\" rpy=\"0 0 1.5707963267948966\"/></joint>\
             <joint name=\"j_lens\" type=\"fixed\"><parent link=\"cam\"/><child link=\"lens\"/>\
             <origin xyz=\"0.2 0 0\" rpy=\"0 0 0\"/></joint></robot>",
        );
        let r = Robot::from_urdf_str(&text).unwrap();
        let lens = r.link_frames().iter().find(|f| f.name == "lens").unwrap();
        assert_eq!(lens.body, Some(1));
        // 0.1 along x, then 0.2 along the camera's x = the body's y.
        assert!((lens.pose.pos - nalgebra::Vector3::new(0.1, 0.2, 0.0)).norm() < 1e-12);
    }
}
