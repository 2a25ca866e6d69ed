//! `include/cablevib_ipc.h` agrees with the Rust layout and constants.
//!
//! The constants are checked by parsing the header (always). The layout is checked by
//! compiling a C program that prints `sizeof`, `_Alignof`, `offsetof`, field sizes, element
//! types and array lengths of every struct, plus the constants as the compiler sees them; its
//! output must equal the same text generated from [`cablevib_ipc::layout::ALL_LAYOUTS`]. When
//! no C compiler is found (`$CC`, `cc`, `gcc`, `clang`) that test prints why and passes. A C++
//! compile checks the `IOX2_TYPE_NAME` members used by iceoryx2-cxx, when a C++ compiler exists.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use cablevib_ipc::layout::{StructLayout, ALL_LAYOUTS};
use cablevib_ipc::{
    MeasuredStatus, StatusCode, ALL_SERVICES, EVENT_ID_ESTIMATE, EVENT_ID_MARGIN_REQUEST,
    EVENT_ID_MARGIN_RESPONSE, EVENT_ID_POSE, EVENT_ID_T_MIN, EVENT_ID_VIBRATION, MAX_CABLES,
    MAX_STIFFNESS_DIM, SCHEMA_VERSION, SERVICE_ESTIMATE, SERVICE_MARGIN, SERVICE_POSE,
    SERVICE_T_MIN, SERVICE_VIBRATION, SERVICE_WAKE_CONTROLLER, SERVICE_WAKE_SERVICE,
};

fn include_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("include")
}

fn header_text() -> String {
    std::fs::read_to_string(include_dir().join("cablevib_ipc.h")).expect("read the header")
}

/// `cablevib_pose_sample_t` → `POSE_SAMPLE` (suffix of `CABLEVIB_TYPE_NAME_*`).
fn c_stem(c_name: &str) -> String {
    c_name
        .strip_prefix("cablevib_")
        .and_then(|s| s.strip_suffix("_t"))
        .expect("C names are cablevib_*_t")
        .to_ascii_uppercase()
}

fn status_c_name(code: StatusCode) -> String {
    format!("CABLEVIB_STATUS_{}", code.as_str().to_ascii_uppercase())
}

fn measured_c_name(code: MeasuredStatus) -> String {
    format!("CABLEVIB_MEASURED_{}", code.as_str().to_ascii_uppercase())
}

/// Every constant the header must define, as (C name, value as C would print it).
fn expected_constants() -> Vec<(String, String)> {
    let mut v = vec![
        ("CABLEVIB_SCHEMA_VERSION".into(), SCHEMA_VERSION.to_string()),
        ("CABLEVIB_MAX_CABLES".into(), MAX_CABLES.to_string()),
        (
            "CABLEVIB_AGE_UNKNOWN".into(),
            cablevib_ipc::EE_MODE_AGE_UNKNOWN.to_string(),
        ),
        (
            "CABLEVIB_AGE_UNKNOWN".into(),
            cablevib_ipc::T_MIN_AGE_UNKNOWN.to_string(),
        ),
        (
            "CABLEVIB_REQUIRED_F1_MIN_HZ".into(),
            format!("{:e}", cablevib_ipc::REQUIRED_F1_MIN_HZ),
        ),
        (
            "CABLEVIB_REQUIRED_F1_MAX_HZ".into(),
            format!("{:e}", cablevib_ipc::REQUIRED_F1_MAX_HZ),
        ),
        (
            "CABLEVIB_MAX_STIFFNESS_DIM".into(),
            MAX_STIFFNESS_DIM.to_string(),
        ),
        (
            "CABLEVIB_SERVICE_POSE".into(),
            format!("\"{SERVICE_POSE}\""),
        ),
        (
            "CABLEVIB_SERVICE_T_MIN".into(),
            format!("\"{SERVICE_T_MIN}\""),
        ),
        (
            "CABLEVIB_SERVICE_ESTIMATE".into(),
            format!("\"{SERVICE_ESTIMATE}\""),
        ),
        (
            "CABLEVIB_SERVICE_MARGIN".into(),
            format!("\"{SERVICE_MARGIN}\""),
        ),
        (
            "CABLEVIB_SERVICE_VIBRATION".into(),
            format!("\"{SERVICE_VIBRATION}\""),
        ),
        (
            "CABLEVIB_EVENT_ID_VIBRATION".into(),
            EVENT_ID_VIBRATION.to_string(),
        ),
        (
            "CABLEVIB_MEASURED_AGE_UNKNOWN".into(),
            cablevib_ipc::MEASURED_AGE_UNKNOWN.to_string(),
        ),
        (
            "CABLEVIB_VIBRATION_FLAG_ANGULAR_VELOCITY".into(),
            cablevib_ipc::VIBRATION_FLAG_ANGULAR_VELOCITY.to_string(),
        ),
        (
            "CABLEVIB_SERVICE_WAKE_SERVICE".into(),
            format!("\"{SERVICE_WAKE_SERVICE}\""),
        ),
        (
            "CABLEVIB_SERVICE_WAKE_CONTROLLER".into(),
            format!("\"{SERVICE_WAKE_CONTROLLER}\""),
        ),
        ("CABLEVIB_EVENT_ID_POSE".into(), EVENT_ID_POSE.to_string()),
        ("CABLEVIB_EVENT_ID_T_MIN".into(), EVENT_ID_T_MIN.to_string()),
        (
            "CABLEVIB_EVENT_ID_MARGIN_REQUEST".into(),
            EVENT_ID_MARGIN_REQUEST.to_string(),
        ),
        (
            "CABLEVIB_EVENT_ID_ESTIMATE".into(),
            EVENT_ID_ESTIMATE.to_string(),
        ),
        (
            "CABLEVIB_EVENT_ID_MARGIN_RESPONSE".into(),
            EVENT_ID_MARGIN_RESPONSE.to_string(),
        ),
    ];
    assert_eq!(
        ALL_SERVICES.len(),
        5,
        "a new service needs a header constant and a line here"
    );
    for l in ALL_LAYOUTS {
        v.push((
            format!("CABLEVIB_TYPE_NAME_{}", c_stem(l.c_name)),
            format!("\"{}\"", l.type_name),
        ));
    }
    v
}

/// `#define CABLEVIB_X value` lines and `CABLEVIB_STATUS_X = N` enumerators of the header.
fn parse_header() -> (BTreeMap<String, String>, BTreeMap<String, u32>) {
    let text = header_text();
    let mut defines = BTreeMap::new();
    let mut statuses = BTreeMap::new();
    for line in text.lines() {
        let line = line.split("/*").next().unwrap().trim();
        if let Some(rest) = line.strip_prefix("#define ") {
            let mut parts = rest.splitn(2, char::is_whitespace);
            let name = parts.next().unwrap();
            let value = parts.next().unwrap_or("").trim();
            if !name.contains('(') {
                defines.insert(name.to_owned(), value.trim_end_matches('u').to_owned());
            }
        } else if line.starts_with("CABLEVIB_STATUS_") || line.starts_with("CABLEVIB_MEASURED_") {
            let (name, value) = line
                .trim_end_matches(',')
                .split_once('=')
                .expect("NAME = N");
            statuses.insert(
                name.trim().to_owned(),
                value.trim().parse().expect("number"),
            );
        }
    }
    (defines, statuses)
}

#[test]
fn header_constants_match_rust() {
    let (defines, statuses) = parse_header();
    for (name, value) in expected_constants() {
        assert_eq!(defines.get(&name), Some(&value), "{name} in cablevib_ipc.h");
    }
    let expected: BTreeMap<String, u32> = StatusCode::ALL
        .iter()
        .map(|&c| (status_c_name(c), c.as_u32()))
        .chain(
            MeasuredStatus::ALL
                .iter()
                .map(|&c| (measured_c_name(c), c.as_u32())),
        )
        .collect();
    assert_eq!(
        statuses, expected,
        "status enum of cablevib_ipc.h vs StatusCode"
    );
}

#[test]
fn header_mentions_every_field_in_order() {
    // A cheap textual check that also runs without a compiler.
    let text = header_text();
    for l in ALL_LAYOUTS {
        let start = text
            .find(&format!(
                "typedef struct {} {{",
                l.c_name.trim_end_matches("_t")
            ))
            .unwrap_or_else(|| panic!("{} not declared", l.c_name));
        let end = start
            + text[start..]
                .find(&format!("}} {};", l.c_name))
                .expect("closing");
        let body = &text[start..end];
        let mut at = 0;
        for f in l.fields {
            let needle = format!(" {}", f.name);
            let pos = body[at..]
                .find(&format!("{needle};"))
                .or_else(|| body[at..].find(&format!("{needle}[")))
                .unwrap_or_else(|| panic!("{}.{} missing or out of order", l.c_name, f.name));
            at += pos + needle.len();
        }
    }
}

fn find_compiler(env: &str, candidates: &[&str]) -> Option<String> {
    let from_env = std::env::var(env).ok().filter(|s| !s.trim().is_empty());
    from_env
        .into_iter()
        .chain(candidates.iter().map(|s| s.to_string()))
        .find(|cc| {
            Command::new(cc)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
}

fn scratch_dir(tag: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("cablevib-ipc-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Compiles `source` with `compiler` and `flags`, runs it, returns its stdout.
fn compile_and_run(compiler: &str, flags: &[&str], source: &str, tag: &str, ext: &str) -> String {
    let dir = scratch_dir(tag);
    let src = dir.join(format!("layout.{ext}"));
    let exe = dir.join("layout");
    std::fs::write(&src, source).unwrap();
    let out = Command::new(compiler)
        .args(flags)
        .arg("-I")
        .arg(include_dir())
        .arg(&src)
        .arg("-o")
        .arg(&exe)
        .output()
        .unwrap_or_else(|e| panic!("running {compiler}: {e}"));
    let run = out
        .status
        .success()
        .then(|| Command::new(&exe).output().expect("run the layout program"));
    let _ = std::fs::remove_dir_all(&dir);
    let run = run.unwrap_or_else(|| {
        panic!(
            "{compiler} failed on this program:\n{source}\n{}",
            String::from_utf8_lossy(&out.stderr)
        )
    });
    assert!(run.status.success(), "layout program failed");
    String::from_utf8(run.stdout).unwrap()
}

/// A constant as the C program prints it: a double (`1e-6`) as `%g` does (`1e-06`; the
/// double constants are powers of ten), anything else as is.
fn c_printed(value: &str) -> String {
    if value.starts_with('"') || !value.contains('e') {
        return value.to_owned();
    }
    let x: f64 = value.parse().expect("a double");
    let exp = x.log10().round() as i32;
    assert_eq!(
        x,
        format!("1e{exp}").parse::<f64>().unwrap(),
        "{value}: a power of ten"
    );
    format!("1e{}{:02}", if exp < 0 { '-' } else { '+' }, exp.abs())
}

/// The lines both the C program and the Rust table produce.
fn struct_line(l: &StructLayout) -> String {
    format!("struct {} size {} align {}", l.c_name, l.size, l.align)
}

fn expected_output() -> String {
    let mut s = String::new();
    for l in ALL_LAYOUTS {
        s += &struct_line(&l);
        s += "\n";
        for f in l.fields {
            s += &format!(
                "field {}.{} offset {} size {} elem {} len {}\n",
                l.c_name, f.name, f.offset, f.size, f.elem, f.len
            );
        }
    }
    for (name, value) in expected_constants() {
        s += &format!("const {name} {}\n", c_printed(&value));
    }
    for c in StatusCode::ALL {
        s += &format!("const {} {}\n", status_c_name(c), c.as_u32());
    }
    for c in MeasuredStatus::ALL {
        s += &format!("const {} {}\n", measured_c_name(c), c.as_u32());
    }
    s
}

fn c_program() -> String {
    let mut p = String::from(
        "#include <stdio.h>\n#include <stddef.h>\n#include <stdint.h>\n\
         #include \"cablevib_ipc.h\"\n\
         #define ELEM(x) _Generic((x), uint32_t: \"u32\", uint64_t: \"u64\", \
         double: \"f64\", default: \"other\")\n\
         int main(void) {\n",
    );
    for l in ALL_LAYOUTS {
        let t = l.c_name;
        p += &format!(
            "  printf(\"struct {t} size %zu align %zu\\n\", sizeof({t}), (size_t)_Alignof({t}));\n"
        );
        for f in l.fields {
            let m = format!("((({t} *)0)->{})", f.name);
            // Index arrays, so that a scalar in C where Rust has an array fails to compile and
            // an array in C where Rust has a scalar prints elem "other".
            let (elem, len) = if f.len > 1 {
                (format!("{m}[0]"), format!("sizeof {m} / sizeof {m}[0]"))
            } else {
                (m.clone(), "(size_t)1".to_owned())
            };
            p += &format!(
                "  printf(\"field {t}.{n} offset %zu size %zu elem %s len %zu\\n\", \
                 offsetof({t}, {n}), sizeof {m}, ELEM({elem}), (size_t)({len}));\n",
                n = f.name
            );
        }
    }
    for (name, value) in expected_constants() {
        if value.starts_with('"') {
            p += &format!("  printf(\"const {name} \\\"%s\\\"\\n\", {name});\n");
        } else if value.contains('e') {
            p += &format!("  printf(\"const {name} %g\\n\", (double)({name}));\n");
        } else {
            p += &format!("  printf(\"const {name} %llu\\n\", (unsigned long long)({name}));\n");
        }
    }
    let codes = StatusCode::ALL.iter().map(|&c| status_c_name(c));
    for name in codes.chain(MeasuredStatus::ALL.iter().map(|&c| measured_c_name(c))) {
        p += &format!("  printf(\"const {name} %u\\n\", (unsigned)({name}));\n");
    }
    p += "  return 0;\n}\n";
    p
}

#[test]
fn c_layout_matches_rust() {
    let Some(cc) = find_compiler("CC", &["cc", "gcc", "clang"]) else {
        eprintln!(
            "SKIPPED c_layout_matches_rust: no C compiler found ($CC, cc, gcc, clang); \
             the C header's layout is NOT verified"
        );
        return;
    };
    let flags = ["-std=c11", "-Wall", "-Wextra", "-Wpedantic", "-Werror"];
    let got = compile_and_run(&cc, &flags, &c_program(), "c", "c");
    let want = expected_output();
    if got != want {
        let diff: Vec<String> = want
            .lines()
            .zip(got.lines().chain(std::iter::repeat("<missing>")))
            .filter(|(w, g)| w != g)
            .map(|(w, g)| format!("  rust: {w}\n  C:    {g}"))
            .collect();
        panic!(
            "cablevib_ipc.h disagrees with the Rust layout ({cc}):\n{}",
            diff.join("\n")
        );
    }
}

#[test]
fn cxx_type_names_match_rust() {
    let Some(cxx) = find_compiler("CXX", &["c++", "g++", "clang++"]) else {
        eprintln!(
            "SKIPPED cxx_type_names_match_rust: no C++ compiler found ($CXX, c++, g++, clang++)"
        );
        return;
    };
    let mut p = String::from(
        "#include <cstdio>\n#include <type_traits>\n#include \"cablevib_ipc.h\"\nint main() {\n",
    );
    for l in ALL_LAYOUTS {
        let t = l.c_name;
        p += &format!(
            "  static_assert(std::is_standard_layout<{t}>::value && \
             std::is_trivially_copyable<{t}>::value, \"{t} is POD\");\n  \
             std::printf(\"%s %zu\\n\", {t}::IOX2_TYPE_NAME, sizeof({t}));\n"
        );
    }
    p += "  return 0;\n}\n";
    let flags = ["-std=c++17", "-Wall", "-Wextra", "-Wpedantic", "-Werror"];
    let got = compile_and_run(&cxx, &flags, &p, "cxx", "cpp");
    let want: String = ALL_LAYOUTS
        .iter()
        .map(|l| format!("{} {}\n", l.type_name, l.size))
        .collect();
    assert_eq!(got, want, "IOX2_TYPE_NAME / sizeof in C++ vs Rust");
}
