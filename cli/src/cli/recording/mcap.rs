//! An MCAP recording, streamed by the `mcap` crate's reader (memory: one record or chunk, at
//! most [`MAX_RECORD_BYTES`]).
//!
//! - **Vibration**: the messages of one topic (`--topic`, else the first topic whose schema
//!   is `sensor_msgs/msg/Imu` or `geometry_msgs/msg/WrenchStamped`; a second such topic
//!   without `--topic` is refused). ROS 2 messages (encoding `cdr`, schema `ros2msg`) are
//!   decoded from the schema text the file carries ([`super::ros2`]); JSON messages (a
//!   `cablevib monitor` recording) by their numeric fields. The channels are `--channels`,
//!   else the IMU's `linear_acceleration.{x,y,z}` and `angular_velocity.{x,y,z}`, the
//!   wrench's `wrench.force.{x,y,z}` and `wrench.torque.{x,y,z}`, or every numeric field
//!   of a JSON message but its time and sequence.
//! - **Measured inputs on a topic of their own** (`--input-topic`, e.g. a
//!   `geometry_msgs/msg/WrenchStamped` stream beside the IMU's): the `--input` fields of its
//!   messages come as [`Item::Input`] on their own clock (the command line puts them on the
//!   responses' clock, `cablevib::identify::align`).
//! - **Poses**: `geometry_msgs/msg/PoseStamped` (`--pose-topic`, else the first such topic),
//!   or a monitor recording's `cablevib.Pose`.
//! - **Time**: a ROS 2 message's `header.stamp` (the sensor's time), a JSON message's
//!   `timestamp_ns`, else the record's log time; every time is counted from the first
//!   message read (the JSON output states that origin).
//!
//! A file cut short (no footer, a chunk cut) is an error naming what was read.

use super::ros2::Layout as MsgLayout;
use super::{CliError, Item, Layout, ReadOptions};
use std::collections::HashMap;
use std::path::Path;

/// Largest MCAP record or chunk read, bytes.
pub const MAX_RECORD_BYTES: usize = 256 * 1024 * 1024;

const IMU: &str = "sensor_msgs/msg/Imu";
const WRENCH: &str = "geometry_msgs/msg/WrenchStamped";
const POSE: &str = "geometry_msgs/msg/PoseStamped";
const MONITOR_POSE: &str = "cablevib.Pose";

/// How one channel (MCAP channel id) is decoded.
enum Decoder {
    Ros(MsgLayout),
    Json,
}

/// The role of a channel.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Vibration,
    Input,
    Pose,
    Other,
}

fn default_channels(schema: &str) -> Vec<String> {
    let xyz = |p: &str| ["x", "y", "z"].map(|c| format!("{p}.{c}"));
    match schema {
        IMU => [xyz("linear_acceleration"), xyz("angular_velocity")].concat(),
        WRENCH => [xyz("wrench.force"), xyz("wrench.torque")].concat(),
        _ => Vec::new(),
    }
}

/// Numeric fields of a JSON value, flattened with dotted names and [i] indices.
fn flatten(v: &serde_json::Value, prefix: &str, out: &mut Vec<(String, f64)>) {
    match v {
        serde_json::Value::Number(n) => {
            out.push((prefix.to_string(), n.as_f64().unwrap_or(f64::NAN)))
        }
        serde_json::Value::Null => out.push((prefix.to_string(), f64::NAN)),
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                flatten(x, &format!("{prefix}[{i}]"), out);
            }
        }
        serde_json::Value::Object(o) => {
            for (k, x) in o {
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(x, &p, out);
            }
        }
        _ => {}
    }
}

/// The positions of `wanted` among the message's field names; the first name missing.
fn positions<'w>(wanted: &'w [String], fnames: &[String]) -> Result<Vec<usize>, &'w String> {
    wanted
        .iter()
        .map(|w| fnames.iter().position(|k| k == w).ok_or(w))
        .collect()
}

/// `values` from the message's `vals` at `picks` (a field found again by its name when a
/// sequence of another length moved it); the name missing otherwise.
fn fill<'n>(
    values: &mut [f64],
    picks: &[usize],
    names: &'n [String],
    fnames: &[String],
    vals: &[f64],
) -> Result<(), &'n String> {
    for (v, (&p, n)) in values.iter_mut().zip(picks.iter().zip(names)) {
        *v = match fnames.get(p) {
            Some(k) if k == n => vals[p],
            _ => vals[fnames.iter().position(|k| k == n).ok_or(n)?],
        };
    }
    Ok(())
}

/// Read the MCAP recording `path` (module docs).
pub fn read(
    path: &Path,
    opts: &ReadOptions,
    sink: &mut dyn FnMut(Item<'_>) -> Result<(), CliError>,
) -> Result<(), CliError> {
    let shown = path.display().to_string();
    let bad = |what: String| CliError::Usage(format!("{shown}: {what}"));
    if let Some(t) = &opts.input_topic {
        if opts.inputs.is_empty() {
            return Err(bad(format!(
                "--input-topic {t}: name the input fields with --input (e.g. --input wrench.force.x)"
            )));
        }
        if opts.topic.as_ref() == Some(t) || opts.pose_topic.as_ref() == Some(t) {
            return Err(bad(format!(
                "--input-topic {t} is also the vibration or pose topic: inputs on the vibration topic need no --input-topic"
            )));
        }
    }
    let separate = opts.input_topic.is_some();
    let n_in = opts.inputs.len();
    let f = crate::input_file::open_checked(path, "recording", u64::MAX)
        .map_err(|e| CliError::Usage(e.to_string()))?;
    let options =
        mcap::sans_io::LinearReaderOptions::default().with_record_length_limit(MAX_RECORD_BYTES);
    let reader = mcap::io::MessageReader::new_with_options(std::io::BufReader::new(f), options);
    let mut decoders: HashMap<u16, (Role, Option<Decoder>)> = HashMap::new();
    let mut vib: Option<(String, String)> = None; // (topic, schema)
    let mut pose_topic: Option<String> = None;
    let mut picks: Vec<usize> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    // The field names of each ROS 2 channel (from its first message), of the last JSON
    // message, and the values of the message at hand.
    let mut named: HashMap<u16, Vec<String>> = HashMap::new();
    let mut json_names: Vec<String> = Vec::new();
    let mut vals: Vec<f64> = Vec::new();
    let mut flat: Vec<(String, f64)> = Vec::new();
    let mut values: Vec<f64> = Vec::new();
    let mut origin_ns: Option<i128> = None;
    let mut vib_messages = 0u64;
    let mut input_messages = 0u64;
    let mut input_picks: Vec<usize> = Vec::new();
    let mut input_values: Vec<f64> = vec![0.0; n_in];
    let mut topics_seen: Vec<String> = Vec::new();
    for (read_messages, m) in reader.enumerate() {
        let m = m.map_err(|e| {
            bad(format!(
                "unreadable or cut short after {read_messages} message(s) ({})",
                e.to_string().replace('\n', " ")
            ))
        })?;
        let ch = &m.channel;
        let (schema_name, schema_enc, schema_text) = match &ch.schema {
            Some(s) => (
                s.name.as_str(),
                s.encoding.as_str(),
                String::from_utf8_lossy(&s.data).into_owned(),
            ),
            None => ("", "", String::new()),
        };
        if topics_seen.len() < 1000 && !decoders.contains_key(&ch.id) {
            let seen = format!(
                "{} ({})",
                ch.topic,
                if schema_name.is_empty() {
                    "no schema"
                } else {
                    schema_name
                }
            );
            if !topics_seen.contains(&seen) {
                topics_seen.push(seen);
            }
        }
        let entry = decoders.entry(ch.id).or_insert_with(|| (Role::Other, None));
        if entry.1.is_none() && entry.0 == Role::Other {
            // First message of this channel: its role.
            let is_vib_schema = schema_name == IMU || schema_name == WRENCH;
            let role = match (&opts.topic, &opts.pose_topic) {
                _ if opts.input_topic.as_ref() == Some(&ch.topic) => Role::Input,
                (Some(t), _) if *t == ch.topic => Role::Vibration,
                (_, Some(t)) if *t == ch.topic => Role::Pose,
                (None, _) if is_vib_schema => Role::Vibration,
                (_, None) if schema_name == POSE || schema_name == MONITOR_POSE => Role::Pose,
                _ => Role::Other,
            };
            if role == Role::Other {
                entry.0 = Role::Other;
                entry.1 = Some(Decoder::Json); // marks "seen"; never used
                continue;
            }
            let dec = match ch.message_encoding.as_str() {
                "cdr" => {
                    if schema_enc != "ros2msg" {
                        return Err(bad(format!(
                            "topic {}: schema `{schema_name}` in encoding `{schema_enc}`: only ros2msg schemas are decoded for CDR messages",
                            ch.topic
                        )));
                    }
                    Decoder::Ros(MsgLayout::parse(schema_name, &schema_text).map_err(|e| bad(format!("topic {}: {e}", ch.topic)))?)
                }
                "json" => Decoder::Json,
                enc => {
                    return Err(bad(format!(
                        "topic {}: message encoding `{enc}` (schema `{schema_name}`) is not decoded (cdr with a ros2msg schema, or json)",
                        ch.topic
                    )))
                }
            };
            match role {
                Role::Vibration => {
                    if let Some((t, _)) = &vib {
                        return Err(bad(format!(
                            "two vibration topics, {t} and {}: choose one with --topic",
                            ch.topic
                        )));
                    }
                    vib = Some((ch.topic.clone(), schema_name.to_string()));
                }
                Role::Pose => {
                    if let Some(t) = &pose_topic {
                        return Err(bad(format!(
                            "two pose topics, {t} and {}: choose one with --pose-topic",
                            ch.topic
                        )));
                    }
                    pose_topic = Some(ch.topic.clone());
                }
                Role::Input | Role::Other => {}
            }
            *entry = (role, Some(dec));
        }
        let (role, Some(dec)) = (&entry.0, &entry.1) else {
            continue;
        };
        if *role == Role::Other {
            continue;
        }
        let fnames: &Vec<String> = match dec {
            Decoder::Ros(l) => {
                let e = |e: String| bad(format!("topic {}, message {}: {e}", ch.topic, m.sequence));
                l.decode_values(&m.data, &mut vals, None).map_err(e)?;
                // Named once per channel; again when a sequence changed the field count.
                if named.get(&ch.id).is_none_or(|v| v.len() != vals.len()) {
                    let mut ns = Vec::new();
                    l.decode_values(&m.data, &mut vals, Some(&mut ns))
                        .map_err(e)?;
                    named.insert(ch.id, ns);
                }
                &named[&ch.id]
            }
            Decoder::Json => {
                let v: serde_json::Value = serde_json::from_slice(&m.data).map_err(|e| {
                    bad(format!(
                        "topic {}: a message is not valid JSON ({e})",
                        ch.topic
                    ))
                })?;
                flat.clear();
                flatten(&v, "", &mut flat);
                json_names.clear();
                json_names.extend(flat.iter().map(|x| x.0.clone()));
                vals.clear();
                vals.extend(flat.iter().map(|x| x.1));
                &json_names
            }
        };
        let get = |n: &str| fnames.iter().position(|k| k == n).map(|i| vals[i]);
        let stamp_ns: i128 = match (
            get("header.stamp.sec"),
            get("header.stamp.nanosec"),
            get("timestamp_ns"),
        ) {
            (Some(s), Some(n), _) if s != 0.0 || n != 0.0 => s as i128 * 1_000_000_000 + n as i128,
            (_, _, Some(t)) => t as i128,
            _ => m.log_time as i128,
        };
        let o = *origin_ns.get_or_insert(stamp_ns);
        let t_s = (stamp_ns - o) as f64 * 1e-9;
        if *role == Role::Vibration {
            if vib_messages == 0 {
                let schema = vib.as_ref().map(|v| v.1.clone()).unwrap_or_default();
                let wanted = if opts.channels.is_empty() {
                    let d = default_channels(&schema);
                    if d.is_empty() {
                        fnames
                            .iter()
                            .filter(|n| {
                                !n.starts_with("header.")
                                    && *n != "timestamp_ns"
                                    && *n != "sequence"
                            })
                            .cloned()
                            .collect()
                    } else {
                        d
                    }
                } else {
                    opts.channels.clone()
                };
                let wanted = opts
                    .with_inputs(wanted)
                    .map_err(|e| bad(format!("topic {}: {e}", ch.topic)))?;
                let on_topic = if separate {
                    &wanted[..wanted.len() - n_in]
                } else {
                    &wanted[..]
                };
                picks = positions(on_topic, fnames).map_err(|w| {
                    bad(format!(
                        "topic {}: no field `{w}`{} (fields: {})",
                        ch.topic,
                        if opts.inputs.contains(w) {
                            " for --input (a measured input is a field of the vibration topic's messages, or of --input-topic's)"
                        } else {
                            ""
                        },
                        fnames.join(", ")
                    ))
                })?;
                if picks.len() <= if separate { 0 } else { n_in } {
                    return Err(bad(format!(
                        "topic {}: no numeric field to identify from",
                        ch.topic
                    )));
                }
                names = on_topic.to_vec();
                values = vec![0.0; picks.len()];
                sink(Item::Layout(&Layout {
                    channels: wanted.clone(),
                    source: format!(
                        "MCAP {shown}, topic {} ({}){}, time origin {:.9} s",
                        ch.topic,
                        if schema_name.is_empty() {
                            "json"
                        } else {
                            schema_name
                        },
                        opts.input_topic
                            .as_ref()
                            .map_or(String::new(), |t| format!(", inputs on topic {t}")),
                        o as f64 * 1e-9
                    ),
                    inputs: n_in,
                    separate_inputs: separate,
                }))?;
            }
            vib_messages += 1;
            fill(&mut values, &picks, &names, fnames, &vals).map_err(|n| {
                bad(format!(
                    "topic {}, message {}: no field `{n}`",
                    ch.topic, m.sequence
                ))
            })?;
            sink(Item::Sample {
                t_s,
                values: &values,
            })?;
        } else if *role == Role::Input {
            if input_messages == 0 {
                input_picks = positions(&opts.inputs, fnames).map_err(|w| {
                    bad(format!(
                        "--input-topic {}: no field `{w}` for --input (fields: {})",
                        ch.topic,
                        fnames.join(", ")
                    ))
                })?;
            }
            input_messages += 1;
            fill(&mut input_values, &input_picks, &opts.inputs, fnames, &vals).map_err(|n| {
                bad(format!(
                    "topic {}, message {}: no field `{n}`",
                    ch.topic, m.sequence
                ))
            })?;
            sink(Item::Input {
                t_s,
                values: &input_values,
            })?;
        } else {
            let pose = if schema_name == MONITOR_POSE {
                let p = |i: usize| get(&format!("position_m[{i}]"));
                let q = |i: usize| get(&format!("orientation_wxyz[{i}]"));
                (p(0), p(1), p(2), [q(0), q(1), q(2), q(3)])
            } else {
                let p = |c: &str| get(&format!("pose.position.{c}"));
                let q = |c: &str| get(&format!("pose.orientation.{c}"));
                (p("x"), p("y"), p("z"), [q("w"), q("x"), q("y"), q("z")])
            };
            let (Some(x), Some(y), Some(z)) = (pose.0, pose.1, pose.2) else {
                return Err(bad(format!(
                    "topic {}: a pose without a position",
                    ch.topic
                )));
            };
            let q = pose.3;
            sink(Item::Pose {
                t_s,
                position_m: [x, y, z],
                orientation_wxyz: q
                    .iter()
                    .all(|v| v.is_some())
                    .then(|| q.map(|v| v.unwrap_or(0.0))),
            })?;
        }
    }
    if vib_messages == 0 {
        let what = match &opts.topic {
            Some(t) => format!("no message on topic {t}"),
            None => format!("no {IMU} or {WRENCH} topic (give --topic)"),
        };
        return Err(bad(format!(
            "{what}; topics in the file: {}",
            if topics_seen.is_empty() {
                "none".to_string()
            } else {
                topics_seen.join(", ")
            }
        )));
    }
    if let (Some(t), 0) = (&opts.input_topic, input_messages) {
        return Err(bad(format!(
            "--input-topic {t}: no message on that topic; topics in the file: {}",
            topics_seen.join(", ")
        )));
    }
    if let (Some(t), None) = (&opts.pose_topic, &pose_topic) {
        return Err(bad(format!("--pose-topic {t}: no message on that topic")));
    }
    Ok(())
}
