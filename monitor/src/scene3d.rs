//! The 3D view: one Foxglove `SceneUpdate` per drawn frame, built from the scene, the latest
//! pose and its estimate.
//!
//! Entities (frame `world`, the scene's base frame; ids stable so each update replaces the
//! previous one):
//!
//! - `anchors`: a sphere at each cable's anchor;
//! - `cables`: cable i as a line from its anchor to its attachment point on the end-effector,
//!   coloured by [`tension_colour`] of its tension between its T_min (the set-point in force,
//!   else the scene's) and its T_max; with sag on, the line follows the elastic catenary
//!   through those points at the cable's estimated end tension ([`PROFILE_POINTS`] points);
//!   grey when the estimate's status is not ok;
//! - `end_effector`: a box through the attachment points with the pose's orientation (rigid
//!   scenes), else a sphere at the position; its metadata names the `pose_sequence`;
//! - `label`: the text "f1 … Hz · margin … Hz" above the end-effector.

use cablevib::elastic_catenary::{CableChord, SagParams};
use cablevib::kinematics::rotation_of;
use cablevib::scene::Scene;
use cablevib_ipc::{
    EstimateSample, PoseSample, TminSetpoint, ATTR_ELEMENTS_PER_CABLE, ATTR_ELEMENT_MODEL,
    ATTR_SCENE,
};
use cablevib_service::ports::ReadAttributes;
use foxglove::messages::{
    Color, CubePrimitive, KeyValuePair, LinePrimitive, Point3, Pose, Quaternion, SceneEntity,
    SceneUpdate, SpherePrimitive, TextPrimitive, Timestamp, Vector3,
};
use nalgebra::Vector3 as V3;

/// The frame every entity is drawn in.
pub const FRAME: &str = "world";
/// Points of a sagged cable's drawn profile.
pub const PROFILE_POINTS: usize = 17;

/// The colour of a cable at tension `t_n` between `t_min_n` (blue, `(0.1, 0.3, 1.0)`) and
/// `t_max_n` (red, `(1.0, 0.1, 0.1)`), linear in u = (t − t_min)/(t_max − t_min) clamped
/// to [0, 1]; opaque. Grey `(0.5, 0.5, 0.5)` for a non-finite tension or empty range.
pub fn tension_colour(t_n: f64, t_min_n: f64, t_max_n: f64) -> Color {
    let range = t_max_n - t_min_n;
    if !(t_n.is_finite() && range.is_finite() && range > 0.0) {
        return grey();
    }
    let u = ((t_n - t_min_n) / range).clamp(0.0, 1.0);
    Color {
        r: 0.1 + 0.9 * u,
        g: 0.3 - 0.2 * u,
        b: 1.0 - 0.9 * u,
        a: 1.0,
    }
}

fn grey() -> Color {
    Color {
        r: 0.5,
        g: 0.5,
        b: 0.5,
        a: 1.0,
    }
}

fn point(v: &V3<f64>) -> Point3 {
    Point3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn pose_at(v: &V3<f64>, q_wxyz: [f64; 4]) -> Pose {
    Pose {
        position: Some(Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }),
        orientation: Some(Quaternion {
            x: q_wxyz[1],
            y: q_wxyz[2],
            z: q_wxyz[3],
            w: q_wxyz[0],
        }),
    }
}

fn entity(id: &str, stamp: Timestamp) -> SceneEntity {
    SceneEntity {
        timestamp: Some(stamp),
        frame_id: FRAME.into(),
        id: id.into(),
        ..Default::default()
    }
}

/// The sagged profile of a cable from `a` to `p` at end tension `t_n`, or `None` when the
/// catenary solve fails (the cable is then drawn straight).
fn sagged_profile(
    scene: &Scene,
    i: usize,
    a: &V3<f64>,
    p: &V3<f64>,
    t_n: f64,
) -> Option<Vec<Point3>> {
    let up = cablevib::kinematics::up_frame(&scene.gravity_m_s2)
        .column(2)
        .into_owned();
    let d = p - a;
    let rise = d.dot(&up);
    let horizontal = d - up * rise;
    let span = horizontal.norm();
    let h = if span > 0.0 {
        horizontal / span
    } else {
        cablevib::kinematics::up_frame(&scene.gravity_m_s2)
            .column(0)
            .into_owned()
    };
    let chord = CableChord {
        span_m: span,
        rise_m: rise,
        ea_n: scene.cables[i].ea_n(),
        w_n_m: scene.weight_per_length_n_m(i),
    };
    let (cat, _) = chord
        .solve_end_tension(t_n, None, &SagParams::default())
        .ok()?;
    Some(
        (0..PROFILE_POINTS)
            .map(|k| {
                let s = cat.l0_m * k as f64 / (PROFILE_POINTS - 1) as f64;
                let [x, z] = cat.point_at_m(s);
                point(&(a + h * x + up * z))
            })
            .collect(),
    )
}

/// The scene the service names in its attributes (`cablevib.scene`), when it is an embedded
/// one (`Scene::builtin`: no file named by another process is read) whose cable element model
/// and elements per cable equal the service's attributes; otherwise why not, in one line.
pub fn scene_of_service(attributes: &ReadAttributes) -> Result<Scene, String> {
    let Some(name) = attributes.get(ATTR_SCENE) else {
        return Err(format!(
            "the service names no scene (no {ATTR_SCENE} attribute: a peer created the \
             services before `cablevib serve`); pass --scene"
        ));
    };
    let scene = match Scene::builtin(name) {
        Some(Ok(s)) => s,
        Some(Err(e)) => return Err(format!("the service's scene {name:?}: {e}")),
        None => {
            return Err(format!(
                "the service's scene {name:?} is not an embedded one; pass its file with --scene"
            ))
        }
    };
    let model = scene.model.element.as_str();
    let elements = scene.model.elements_per_cable.to_string();
    for (key, ours) in [
        (ATTR_ELEMENT_MODEL, model),
        (ATTR_ELEMENTS_PER_CABLE, elements.as_str()),
    ] {
        match attributes.get(key) {
            Some(theirs) if theirs != ours => {
                return Err(format!(
                    "the service runs {name:?} with {key} = {theirs}, the embedded scene has \
                     {ours}; pass --scene with the service's options"
                ))
            }
            _ => {}
        }
    }
    Ok(scene)
}

/// Wall-clock stamp (ns since the Unix epoch) as a Foxglove timestamp.
pub fn stamp(unix_ns: u64) -> Timestamp {
    Timestamp::new(
        (unix_ns / 1_000_000_000) as u32,
        (unix_ns % 1_000_000_000) as u32,
    )
}

/// The update for `estimate` at `pose` (the pose it answers), with the T_min set-point in
/// force (`None`: the scene's) and the monitor's margin (`margin_hz`, NaN when none).
pub fn scene_update(
    scene: &Scene,
    pose: &PoseSample,
    estimate: &EstimateSample,
    t_min: Option<&TminSetpoint>,
    margin_hz: f64,
    time: Timestamp,
) -> SceneUpdate {
    let p = V3::from(pose.position_m);
    let q = pose.orientation_wxyz;
    let r = rotation_of(&q);
    let ends: Vec<V3<f64>> = scene
        .cables
        .iter()
        .map(|c| {
            if scene.rigid {
                p + r * c.attachment_m
            } else {
                p
            }
        })
        .collect();

    let mut anchors = entity("anchors", time);
    anchors.spheres = scene
        .cables
        .iter()
        .map(|c| SpherePrimitive {
            pose: Some(pose_at(&c.anchor_m, [1.0, 0.0, 0.0, 0.0])),
            size: Some(Vector3 {
                x: 0.04,
                y: 0.04,
                z: 0.04,
            }),
            color: Some(Color {
                r: 0.2,
                g: 0.2,
                b: 0.2,
                a: 1.0,
            }),
        })
        .collect();

    let ok = estimate.is_ok();
    let tensions = estimate.tensions();
    let mut cables = entity("cables", time);
    for (i, c) in scene.cables.iter().enumerate() {
        let t = if ok { tensions.get(i).copied() } else { None };
        let t_min = t_min.map_or(scene.cable_t_min_n(i), |s| s.t_min_for(i));
        let colour = t.map_or_else(grey, |t| tension_colour(t, t_min, scene.cable_t_max_n(i)));
        let straight = vec![point(&c.anchor_m), point(&ends[i])];
        let points = match t {
            Some(t) if scene.model.sag => {
                sagged_profile(scene, i, &c.anchor_m, &ends[i], t).unwrap_or(straight)
            }
            _ => straight,
        };
        cables.lines.push(LinePrimitive {
            r#type: foxglove::messages::line_primitive::Type::LineStrip as i32,
            pose: Some(pose_at(&V3::zeros(), [1.0, 0.0, 0.0, 0.0])),
            thickness: 3.0,
            scale_invariant: true,
            points,
            color: Some(colour),
            ..Default::default()
        });
    }
    cables.metadata.push(KeyValuePair {
        key: "pose_sequence".into(),
        value: estimate.pose_sequence.to_string(),
    });

    let mut ee = entity("end_effector", time);
    ee.metadata.push(KeyValuePair {
        key: "pose_sequence".into(),
        value: pose.sequence.to_string(),
    });
    let ee_colour = Color {
        r: 0.9,
        g: 0.7,
        b: 0.1,
        a: 0.8,
    };
    if scene.rigid {
        // The box through the body-frame attachment points (at least 2 cm a side).
        let mut half = V3::new(0.01, 0.01, 0.01);
        for c in &scene.cables {
            half = half.sup(&c.attachment_m.abs());
        }
        ee.cubes.push(CubePrimitive {
            pose: Some(pose_at(&p, q)),
            size: Some(Vector3 {
                x: 2.0 * half.x,
                y: 2.0 * half.y,
                z: 2.0 * half.z,
            }),
            color: Some(ee_colour),
        });
    } else {
        ee.spheres.push(SpherePrimitive {
            pose: Some(pose_at(&p, q)),
            size: Some(Vector3 {
                x: 0.06,
                y: 0.06,
                z: 0.06,
            }),
            color: Some(ee_colour),
        });
    }

    let mut label = entity("label", time);
    let margin = if margin_hz.is_finite() {
        format!(" · margin {margin_hz:+.3} Hz")
    } else {
        String::new()
    };
    label.texts.push(TextPrimitive {
        pose: Some(pose_at(
            &(p + V3::new(0.0, 0.0, 0.15)),
            [1.0, 0.0, 0.0, 0.0],
        )),
        billboard: true,
        font_size: 14.0,
        scale_invariant: true,
        color: Some(Color {
            r: 1.0,
            g: 1.0,
            b: 1.0,
            a: 1.0,
        }),
        text: if ok {
            format!("f1 {:.3} Hz{margin}", estimate.f1_hz)
        } else {
            format!("{}", cablevib_ipc::status_str(estimate.status))
        },
    });

    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![anchors, cables, ee, label],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cablevib_ipc::{StatusCode, IDENTITY_QUATERNION};

    #[test]
    fn colours_span_blue_to_red() {
        let lo = tension_colour(10.0, 10.0, 110.0);
        let hi = tension_colour(200.0, 10.0, 110.0);
        let mid = tension_colour(60.0, 10.0, 110.0);
        // The map's endpoints and midpoint, to the rounding of its three operations (≤ 1e-15).
        let near = |c: &Color, rgb: [f64; 3]| {
            (c.r - rgb[0]).abs() <= 1e-15
                && (c.g - rgb[1]).abs() <= 1e-15
                && (c.b - rgb[2]).abs() <= 1e-15
        };
        assert!(near(&lo, [0.1, 0.3, 1.0]), "{lo:?}");
        assert!(near(&hi, [1.0, 0.1, 0.1]), "{hi:?}");
        assert!(near(&mid, [0.55, 0.2, 0.55]), "{mid:?}");
        assert_eq!(tension_colour(f64::NAN, 0.0, 1.0).r, 0.5);
    }

    #[test]
    fn sagged_profile_ends_at_the_anchor_and_the_attachment() {
        let mut scene = Scene::default_scene();
        scene
            .set_sag(true)
            .expect("the paper's FEM scene takes sag");
        let a = scene.cables[0].anchor_m;
        let p = scene.ee_position_m;
        let line = sagged_profile(&scene, 0, &a, &p, 500.0).expect("solves");
        let (first, last) = (&line[0], &line[PROFILE_POINTS - 1]);
        // The catenary's end point meets the chord to the solver's tolerance (≤ 1e-9 of the
        // chord length with the default parameters); 1e-6 m is far above that and far below
        // a drawn pixel.
        assert!((first.x - a.x).abs() + (first.y - a.y).abs() + (first.z - a.z).abs() < 1e-12);
        assert!((last.x - p.x).abs() + (last.y - p.y).abs() + (last.z - p.z).abs() < 1e-6);
        // It hangs below the chord's midpoint.
        let mid = &line[PROFILE_POINTS / 2];
        assert!(mid.z < 0.5 * (a.z + p.z));
    }

    #[test]
    fn not_ok_estimates_draw_grey_cables() {
        let scene = Scene::default_scene();
        let pose = PoseSample::new(1, 0, scene.ee_position_m.into(), IDENTITY_QUATERNION);
        let e = EstimateSample::with_status(StatusCode::InvalidInput);
        let u = scene_update(&scene, &pose, &e, None, f64::NAN, stamp(0));
        let cables = &u.entities[1];
        assert_eq!(cables.lines.len(), scene.n_cables());
        assert!(cables
            .lines
            .iter()
            .all(|l| l.color.as_ref().unwrap().r == 0.5));
    }
}
