//! ROS 2 messages in CDR, decoded from the `ros2msg` schema text an MCAP file carries.
//!
//! A schema is the message's definition followed by its dependencies, each after a line of
//! `=` and a line `MSG: pkg/Type`. A field line is `TYPE NAME` (constants `TYPE NAME=VALUE`
//! and comments are skipped); TYPE is a primitive, `string` (`string<=N`), a nested type
//! (`pkg/Type`, `pkg/msg/Type` or a type of the same package), and any of these as a fixed
//! array `T[N]`, a sequence `T[]` or a bounded sequence `T[<=N]`.
//!
//! CDR (XCDR1, as ROS 2's rmw writes it): a 4-byte encapsulation header (byte 1: 0 big-,
//! 1 little-endian), then the fields in order, each primitive aligned to its size (relative
//! to the end of the header), strings and sequences as a `uint32` length then the elements
//! (a string's length counts its terminating NUL). [`Layout::decode`] walks a message and
//! yields every numeric field under its dotted name (`linear_acceleration.x`,
//! `orientation_covariance[3]`, `header.stamp.sec`); strings are skipped.

use std::collections::BTreeMap;

/// Most fields a decoded message may have (a bound on work per message).
pub const MAX_FIELDS: usize = 4096;
/// Deepest nesting of message types.
const MAX_DEPTH: usize = 16;

#[derive(Debug, Clone, PartialEq)]
enum Base {
    Prim(&'static str, usize),
    Str,
    Msg(String),
}

#[derive(Debug, Clone, PartialEq)]
enum Count {
    One,
    Fixed(usize),
    Seq,
}

#[derive(Debug, Clone, PartialEq)]
struct Field {
    name: String,
    base: Base,
    count: Count,
}

/// A message type and its dependencies, parsed from the schema text.
#[derive(Debug, Clone)]
pub struct Layout {
    root: String,
    types: BTreeMap<String, Vec<Field>>,
}

fn prim(t: &str) -> Option<(&'static str, usize)> {
    Some(match t {
        "bool" => ("bool", 1),
        "byte" | "octet" => ("byte", 1),
        "char" | "uint8" => ("uint8", 1),
        "int8" => ("int8", 1),
        "int16" => ("int16", 2),
        "uint16" => ("uint16", 2),
        "int32" => ("int32", 4),
        "uint32" => ("uint32", 4),
        "int64" => ("int64", 8),
        "uint64" => ("uint64", 8),
        "float32" => ("float32", 4),
        "float64" => ("float64", 8),
        _ => return None,
    })
}

/// `pkg/msg/Type` or `pkg/Type` → `pkg/Type`; a bare `Type` takes `pkg`.
fn full_name(t: &str, pkg: &str) -> String {
    let parts: Vec<&str> = t.split('/').collect();
    match parts[..] {
        [p, "msg", n] => format!("{p}/{n}"),
        [p, n] => format!("{p}/{n}"),
        ["Header"] => "std_msgs/Header".into(),
        [n] => format!("{pkg}/{n}"),
        _ => t.to_string(),
    }
}

impl Layout {
    /// Parse the schema of `name` (e.g. `sensor_msgs/msg/Imu`) from its `ros2msg` text.
    pub fn parse(name: &str, text: &str) -> Result<Layout, String> {
        let root = full_name(name, "");
        let mut types = BTreeMap::new();
        let mut current = root.clone();
        let mut fields: Vec<Field> = Vec::new();
        for raw in text.lines() {
            let line = raw.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            if line.chars().all(|c| c == '=') {
                types.insert(std::mem::take(&mut current), std::mem::take(&mut fields));
                continue;
            }
            if let Some(t) = line.strip_prefix("MSG:") {
                current = full_name(t.trim(), "");
                continue;
            }
            let mut it = line.split_whitespace();
            let (Some(ty), Some(fname)) = (it.next(), it.next()) else {
                return Err(format!("schema {name}: cannot read the line `{line}`"));
            };
            if fname.contains('=') || it.clone().next().is_some_and(|s| s.starts_with('=')) {
                continue; // a constant
            }
            let pkg = current.split('/').next().unwrap_or("").to_string();
            let (base_t, count) = match ty.find('[') {
                Some(i) => {
                    let inner = &ty[i + 1..ty.len().saturating_sub(1)];
                    let c = if inner.is_empty() || inner.starts_with("<=") {
                        Count::Seq
                    } else {
                        Count::Fixed(
                            inner
                                .parse()
                                .map_err(|_| format!("schema {name}: bad array size in `{ty}`"))?,
                        )
                    };
                    (&ty[..i], c)
                }
                None => (ty, Count::One),
            };
            let base_t = base_t.split("<=").next().unwrap_or(base_t);
            let base = if let Some((p, n)) = prim(base_t) {
                Base::Prim(p, n)
            } else if base_t == "string" || base_t == "wstring" {
                if base_t == "wstring" {
                    return Err(format!("schema {name}: wstring fields are not supported"));
                }
                Base::Str
            } else {
                Base::Msg(full_name(base_t, &pkg))
            };
            fields.push(Field {
                name: fname.to_string(),
                base,
                count,
            });
        }
        types.insert(current, fields);
        // The standard types ROS 2 leaves out of some schemas.
        types
            .entry("builtin_interfaces/Time".into())
            .or_insert_with(|| {
                vec![
                    Field {
                        name: "sec".into(),
                        base: Base::Prim("int32", 4),
                        count: Count::One,
                    },
                    Field {
                        name: "nanosec".into(),
                        base: Base::Prim("uint32", 4),
                        count: Count::One,
                    },
                ]
            });
        let l = Layout { root, types };
        l.check(&l.root, 0)?;
        Ok(l)
    }

    fn check(&self, t: &str, depth: usize) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "schema {}: nested deeper than {MAX_DEPTH}",
                self.root
            ));
        }
        let f = self
            .types
            .get(t)
            .ok_or_else(|| format!("schema {}: the type {t} is not defined in it", self.root))?;
        for x in f {
            if let Base::Msg(m) = &x.base {
                self.check(m, depth + 1)?;
            }
        }
        Ok(())
    }

    /// Decode one CDR message: `out` gets (name, value) of every numeric field, in order.
    pub fn decode(&self, data: &[u8], out: &mut Vec<(String, f64)>) -> Result<(), String> {
        let mut values = Vec::new();
        let mut names = Vec::new();
        self.decode_values(data, &mut values, Some(&mut names))?;
        out.clear();
        out.extend(names.into_iter().zip(values));
        Ok(())
    }

    /// Decode one CDR message's numeric values in order into `values` (and their dotted
    /// names into `names` when given: naming every field costs an allocation each).
    pub fn decode_values(
        &self,
        data: &[u8],
        values: &mut Vec<f64>,
        mut names: Option<&mut Vec<String>>,
    ) -> Result<(), String> {
        values.clear();
        if let Some(n) = names.as_deref_mut() {
            n.clear();
        }
        if data.len() < 4 {
            return Err("a message shorter than its 4-byte CDR header".into());
        }
        let le = match data[1] {
            0 | 2 => false,
            1 | 3 => true,
            k => return Err(format!("unknown CDR encapsulation kind {k}")),
        };
        let mut r = Cursor {
            d: &data[4..],
            pos: 0,
            le,
        };
        self.walk(&self.root, "", &mut r, values, &mut names, 0)
    }

    fn walk(
        &self,
        t: &str,
        prefix: &str,
        r: &mut Cursor<'_>,
        out: &mut Vec<f64>,
        names: &mut Option<&mut Vec<String>>,
        depth: usize,
    ) -> Result<(), String> {
        if depth > MAX_DEPTH {
            return Err(format!("{t}: nested deeper than {MAX_DEPTH}"));
        }
        let fields = &self.types[t];
        let named = names.is_some();
        for f in fields {
            let name = match (named, prefix.is_empty()) {
                (false, _) => String::new(),
                (true, true) => f.name.clone(),
                (true, false) => format!("{prefix}.{}", f.name),
            };
            let n = match f.count {
                Count::One => None,
                Count::Fixed(n) => Some(n),
                Count::Seq => Some(r.u32()? as usize),
            };
            let items = n.unwrap_or(1);
            if items > MAX_FIELDS {
                return Err(format!("{name}: {items} elements, over {MAX_FIELDS}"));
            }
            for i in 0..items {
                let nm = match (named, n) {
                    (false, _) => String::new(),
                    (true, Some(_)) => format!("{name}[{i}]"),
                    (true, None) => name.clone(),
                };
                match &f.base {
                    Base::Prim(p, size) => {
                        let v = r.prim(p, *size)?;
                        if out.len() >= MAX_FIELDS {
                            return Err(format!("more than {MAX_FIELDS} fields"));
                        }
                        out.push(v);
                        if let Some(ns) = names.as_deref_mut() {
                            ns.push(nm);
                        }
                    }
                    Base::Str => {
                        let len = r.u32()? as usize;
                        r.skip(len)?;
                    }
                    Base::Msg(m) => self.walk(m, &nm, r, out, names, depth + 1)?,
                }
            }
        }
        Ok(())
    }
}

struct Cursor<'a> {
    d: &'a [u8],
    pos: usize,
    le: bool,
}

impl Cursor<'_> {
    fn take(&mut self, n: usize, align: usize) -> Result<&[u8], String> {
        let a = self.pos.div_ceil(align) * align;
        let end = a
            .checked_add(n)
            .filter(|&e| e <= self.d.len())
            .ok_or_else(|| {
                format!(
                    "the message ends at byte {} before its fields do",
                    self.d.len() + 4
                )
            })?;
        self.pos = end;
        Ok(&self.d[a..end])
    }
    fn skip(&mut self, n: usize) -> Result<(), String> {
        self.take(n, 1).map(|_| ())
    }
    fn u32(&mut self) -> Result<u32, String> {
        let b: [u8; 4] = self.take(4, 4)?.try_into().expect("4 bytes");
        Ok(if self.le {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }
    fn prim(&mut self, p: &str, size: usize) -> Result<f64, String> {
        let le = self.le;
        let b = self.take(size, size)?;
        macro_rules! num {
            ($t:ty) => {{
                let a: [u8; std::mem::size_of::<$t>()] = b.try_into().expect("size");
                (if le {
                    <$t>::from_le_bytes(a)
                } else {
                    <$t>::from_be_bytes(a)
                }) as f64
            }};
        }
        Ok(match p {
            "bool" | "byte" | "uint8" => b[0] as f64,
            "int8" => b[0] as i8 as f64,
            "int16" => num!(i16),
            "uint16" => num!(u16),
            "int32" => num!(i32),
            "uint32" => num!(u32),
            "int64" => num!(i64),
            "uint64" => num!(u64),
            "float32" => num!(f32),
            _ => num!(f64),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const IMU: &str = "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance # row major\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n================================================================================\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";

    /// A hand-laid little-endian Imu (header with a 5-byte frame id, so the doubles after it
    /// need padding) decodes to its values.
    #[test]
    fn imu_by_hand() {
        let l = Layout::parse("sensor_msgs/msg/Imu", IMU).unwrap();
        let mut d = vec![0u8, 1, 0, 0];
        d.extend(7i32.to_le_bytes());
        d.extend(500u32.to_le_bytes());
        d.extend(5u32.to_le_bytes());
        d.extend(b"imu0\0");
        // offset after header: 4 + 4 + 4 + 5 = 17 → pad to 24
        d.extend([0u8; 7]);
        let mut vals = Vec::new();
        for i in 0..(4 + 9 + 3 + 9 + 3 + 9) {
            vals.push(i as f64 * 0.5);
        }
        for v in &vals {
            d.extend(v.to_le_bytes());
        }
        let mut out = Vec::new();
        l.decode(&d, &mut out).unwrap();
        let get = |n: &str| out.iter().find(|(k, _)| k == n).unwrap().1;
        assert_eq!(get("header.stamp.sec"), 7.0);
        assert_eq!(get("header.stamp.nanosec"), 500.0);
        assert_eq!(get("orientation.w"), 1.5);
        assert_eq!(get("angular_velocity.y"), vals[14]);
        assert_eq!(get("linear_acceleration.z"), vals[27]);
        assert_eq!(out.len(), 2 + vals.len());
        // Cut short: one line, no panic.
        assert!(l.decode(&d[..40], &mut out).is_err());
    }

    #[test]
    fn undefined_type_refused() {
        let e = Layout::parse("a/msg/B", "pkg/Missing m\n").unwrap_err();
        assert!(e.contains("pkg/Missing"), "{e}");
    }
}
