//! Property tests of the scene parser against bad input: mutations of
//! scenes/spatial_paper.toml (truncated at a random byte, numbers replaced by huge, tiny,
//! NaN, infinite, negative, string or array values, keys deleted, lines duplicated or
//! swapped, garbage inserted) and random text. Always `Ok` or an `Err` whose message names
//! the file; never a panic. An `Ok` scene is valid (the invariants `Scene` promises, including
//! the derived μ = w/|g| and EA = E·A finite and > 0), and an
//! estimator built on it answers its default pose and a few others with a status, never a
//! panic and never NaN in an ok estimate. Every fixed-size array key of the format, made too
//! long, too short, of mixed types or with a trailing NaN, is refused with a message that
//! names the key and says what is wrong. Fixed seed, no failure persistence.
use cablevib::estimator::Tmin;
use cablevib::estimator::{Estimator, Status};
use cablevib::kinematics::Pose;
use cablevib::scene::{
    Scene, BOX_SCENE_TOML, DEFAULT_SCENE_TOML, MAX_CABLES, MAX_ELEMENTS_PER_CABLE,
    PLANAR_SCENE_TOML,
};
use cablevib_testkit::ee_hz;
use nalgebra::Vector3;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

const FILE: &str = "fuzz/mutated_scene.toml";

fn config(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x5CE7_E006),
        failure_persistence: None,
        max_shrink_iters: 500,
        ..Config::default()
    }
}

/// Values a number may be replaced with.
const REPLACEMENTS: &[&str] = &[
    "nan",
    "+nan",
    "-nan",
    "inf",
    "+inf",
    "-inf",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e-308",
    "5e-324",
    "0",
    "0.0",
    "-0.0",
    "-1",
    "-1e-9",
    "1e9",
    "1e18",
    "9223372036854775807",
    "-9223372036854775808",
    "99999999999999999999",
    "1e400",
    "0x10",
    "1_000",
    "\"12\"",
    "\"\"",
    "true",
    "[]",
    "[1.0]",
    "[1.0, 2.0, 3.0, 4.0]",
    "{}",
    "{ a = 1 }",
    "1979-05-27",
    "'nan'",
    "1e",
    ".5",
    "5.",
    "+",
    "--1",
];

/// Byte offsets and lengths of the numeric literals in `text` (outside comments).
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut in_comment = false;
    while i < b.len() {
        let c = b[i];
        if c == b'#' {
            in_comment = true;
        } else if c == b'\n' {
            in_comment = false;
        }
        let starts = !in_comment
            && (c.is_ascii_digit() || (c == b'-' && i + 1 < b.len() && b[i + 1].is_ascii_digit()))
            && (i == 0
                || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_' || b[i - 1] == b'.'));
        if starts {
            let s = i;
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_digit()
                    || matches!(b[i], b'.' | b'e' | b'E' | b'-' | b'+' | b'_'))
            {
                i += 1;
            }
            out.push((s, i - s));
            continue;
        }
        i += 1;
    }
    out
}

#[derive(Debug, Clone)]
enum Mutation {
    Truncate(usize),
    ReplaceNumber(usize, usize),
    DeleteLine(usize),
    DuplicateLine(usize),
    SwapLines(usize, usize),
    ReplaceValue(usize, usize),
    Insert(usize, String),
    DeleteRange(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 0..REPLACEMENTS.len()).prop_map(|(a, b)| Mutation::ReplaceNumber(a, b)),
        (any::<usize>(), 0..REPLACEMENTS.len()).prop_map(|(a, b)| Mutation::ReplaceNumber(a, b)),
        any::<usize>().prop_map(Mutation::DeleteLine),
        any::<usize>().prop_map(Mutation::DuplicateLine),
        (any::<usize>(), any::<usize>()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        (any::<usize>(), 0..REPLACEMENTS.len()).prop_map(|(a, b)| Mutation::ReplaceValue(a, b)),
        (any::<usize>(), "[ -~\n\t]{0,24}").prop_map(|(a, s)| Mutation::Insert(a, s)),
        (any::<usize>(), 0usize..64).prop_map(|(a, n)| Mutation::DeleteRange(a, n)),
    ]
}

fn floor_boundary(s: &str, i: usize) -> usize {
    let mut i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(text: &str, m: &Mutation) -> String {
    let lines: Vec<&str> = text.split('\n').collect();
    match m {
        Mutation::Truncate(at) => {
            let at = floor_boundary(text, at % (text.len() + 1));
            text[..at].to_string()
        }
        Mutation::ReplaceNumber(k, r) => {
            let nums = numbers(text);
            if nums.is_empty() {
                return text.to_string();
            }
            let (s, l) = nums[k % nums.len()];
            format!("{}{}{}", &text[..s], REPLACEMENTS[*r], &text[s + l..])
        }
        Mutation::DeleteLine(k) => {
            let k = k % lines.len();
            let mut v = lines.clone();
            v.remove(k);
            v.join("\n")
        }
        Mutation::DuplicateLine(k) => {
            let k = k % lines.len();
            let mut v = lines.clone();
            v.insert(k, lines[k]);
            v.join("\n")
        }
        Mutation::SwapLines(a, b) => {
            let mut v = lines.clone();
            let n = v.len();
            v.swap(a % n, b % n);
            v.join("\n")
        }
        Mutation::ReplaceValue(k, r) => {
            let keyed: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains(" = "))
                .collect();
            if keyed.is_empty() {
                return text.to_string();
            }
            let i = keyed[k % keyed.len()];
            let key = lines[i].split(" = ").next().unwrap();
            let mut v: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            v[i] = format!("{key} = {}", REPLACEMENTS[*r]);
            v.join("\n")
        }
        Mutation::Insert(at, s) => {
            let at = floor_boundary(text, at % (text.len() + 1));
            format!("{}{}{}", &text[..at], s, &text[at..])
        }
        Mutation::DeleteRange(at, n) => {
            let a = floor_boundary(text, at % (text.len() + 1));
            let b = floor_boundary(text, (a + n).min(text.len()));
            format!("{}{}", &text[..a], &text[b..])
        }
    }
}

/// The parser's contract on any text, and the estimator's on any scene it accepts.
fn check(text: &str) -> Result<(), TestCaseError> {
    match Scene::from_toml_str(text, FILE) {
        Err(e) => {
            let msg = e.to_string();
            prop_assert!(msg.contains(FILE), "error does not name the file: {msg}");
            prop_assert!(msg.len() > FILE.len() + 4, "error without a reason: {msg}");
        }
        Ok(s) => check_scene(&s)?,
    }
    Ok(())
}

fn check_scene(s: &Scene) -> Result<(), TestCaseError> {
    prop_assert!((2..=MAX_CABLES).contains(&s.n_cables()));
    prop_assert!((1..=MAX_ELEMENTS_PER_CABLE).contains(&s.model.elements_per_cable));
    prop_assert!(s.ee_mass_kg.is_finite() && s.ee_mass_kg > 0.0);
    prop_assert!(
        s.t_min_n.is_finite() && s.t_min_n > 0.0 && s.t_min_n <= s.t_max_n && s.t_max_n.is_finite()
    );
    prop_assert!(s.gravity_m_s2.iter().all(|x| x.is_finite()));
    for c in &s.cables {
        prop_assert!(c.anchor_m.iter().all(|x| x.is_finite()));
        prop_assert!(c.youngs_modulus_pa.is_finite() && c.youngs_modulus_pa > 0.0);
        prop_assert!(c.area_m2.is_finite() && c.area_m2 > 0.0);
        prop_assert!(
            c.mass_per_length_kg_m.is_finite() && c.mass_per_length_kg_m > 0.0,
            "scene accepted with mass per length {:e} kg/m",
            c.mass_per_length_kg_m
        );
        prop_assert!(
            c.ea_n().is_finite() && c.ea_n() > 0.0,
            "scene accepted with EA = {:e} N (E = {:e} Pa, A = {:e} m²)",
            c.ea_n(),
            c.youngs_modulus_pa,
            c.area_m2
        );
    }
    let p = s.model.ee_participation_min;
    prop_assert!(p > 0.0 && p <= 1.0);
    // An estimator on it: built or refused, never a panic; every answer a status.
    if let Ok(mut est) = Estimator::new(s) {
        let centre = s.ee_position_m;
        for (dx, t_min) in [
            (0.0, s.t_min_n),
            (1e-3, s.t_min_n),
            (0.05, 0.5 * s.t_min_n),
            (0.0, s.t_max_n),
        ] {
            let e = *est.update(
                &Pose::at(centre + Vector3::new(dx, -dx, dx)),
                Tmin::Uniform(t_min),
            );
            if e.status == Status::Ok {
                prop_assert!(
                    e.f1_hz.is_finite() && e.f1_hz > 0.0,
                    "ok estimate with f1 {} (scene {:?})",
                    e.f1_hz,
                    s
                );
                prop_assert!(e.tensions().iter().all(|t| t.is_finite()));
                prop_assert!(
                    e.stiffness
                        .translational_n_m()
                        .iter()
                        .all(|x| x.is_finite()),
                    "stiffness {}",
                    e.stiffness.translational_n_m()
                );
                prop_assert!(
                    ee_hz(&e).is_nan()
                        || (ee_hz(&e).is_finite() && ee_hz(&e) >= e.f1_hz * (1.0 - 1e-9)),
                    "ee mode {} below f1 {}",
                    ee_hz(&e),
                    e.f1_hz
                );
            } else {
                prop_assert!(e.f1_hz.is_nan(), "{:?} with f1 {}", e.status, e.f1_hz);
            }
        }
    }
    Ok(())
}

#[test]
fn the_shipped_scenes_parse() {
    for (t, n) in [(DEFAULT_SCENE_TOML, 8), (PLANAR_SCENE_TOML, 4)] {
        let s = Scene::from_toml_str(t, FILE).unwrap();
        assert_eq!(s.n_cables(), n);
        assert!(numbers(t).len() > 20);
    }
}

/// Every value of every key of the spatial scene replaced by every entry of REPLACEMENTS
/// (exhaustive, deterministic: ~40 keys × 40 values).
#[test]
fn every_value_replaced_by_every_bad_value() {
    let text = DEFAULT_SCENE_TOML;
    let lines: Vec<&str> = text.split('\n').collect();
    let keyed = lines.iter().filter(|l| l.contains(" = ")).count();
    let mut texts = Vec::new();
    for k in 0..keyed {
        for (r, bad) in REPLACEMENTS.iter().enumerate() {
            texts.push((
                format!("value {k} := {bad}"),
                apply(text, &Mutation::ReplaceValue(k, r)),
            ));
        }
    }
    for k in 0..numbers(text).len() {
        for (r, bad) in REPLACEMENTS.iter().enumerate() {
            texts.push((
                format!("number {k} := {bad}"),
                apply(text, &Mutation::ReplaceNumber(k, r)),
            ));
        }
    }
    for at in 0..=text.len() {
        texts.push((
            format!("truncated at {at}"),
            apply(text, &Mutation::Truncate(at)),
        ));
    }
    let failures = run_all(&texts);
    eprintln!("{} deterministic mutations checked", texts.len());
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Check every text, collecting failures (a panic counts as one) instead of stopping.
fn run_all(texts: &[(String, String)]) -> Vec<String> {
    let mut failures = Vec::new();
    for (what, t) in texts {
        let r = std::panic::catch_unwind(|| check(t));
        match r {
            Ok(Ok(())) => {}
            Ok(Err(e)) => failures.push(format!("{what}: {e}")),
            Err(_) => failures.push(format!("{what}: PANIC")),
        }
    }
    failures
}

/// Values that are each valid but whose products or quotients are not: a subnormal weight
/// per length (μ = w/|g| underflows to 0), a huge weight over a tiny gravity (μ overflows to
/// ∞), E·A overflowing, a huge mass times g. The scene must be refused with a message naming
/// the key, or be valid (finite positive μ and EA) and answered with statuses.
#[test]
fn derived_quantities_stay_finite_and_positive() {
    let base = DEFAULT_SCENE_TOML;
    let cases: Vec<(&str, String)> = vec![
        (
            "subnormal weight_per_length",
            base.replace("weight_per_length = 0.251", "weight_per_length = 5e-324"),
        ),
        (
            "tiny weight_per_length",
            base.replace("weight_per_length = 0.251", "weight_per_length = 1e-310"),
        ),
        (
            "weight_per_length / tiny gravity overflows",
            base.replace("weight_per_length = 0.251", "weight_per_length = 1e300")
                .replace(
                    "gravity = [0.0, 0.0, -9.81]",
                    "gravity = [0.0, 0.0, -1e-200]",
                ),
        ),
        (
            "E·A overflows",
            base.replace("youngs_modulus = 2.01e10", "youngs_modulus = 1e200")
                .replace("area = 50.265e-6", "area = 1e200"),
        ),
        (
            "E·A underflows",
            base.replace("youngs_modulus = 2.01e10", "youngs_modulus = 1e-200")
                .replace("area = 50.265e-6", "area = 1e-200"),
        ),
        (
            "mass·g overflows",
            base.replace("mass = 30.0", "mass = 1e308"),
        ),
        (
            "subnormal mass",
            base.replace("mass = 30.0", "mass = 5e-324"),
        ),
        (
            "huge mass_per_length",
            base.replace("weight_per_length = 0.251", "mass_per_length = 1e300"),
        ),
        (
            "subnormal mass_per_length",
            base.replace("weight_per_length = 0.251", "mass_per_length = 5e-324"),
        ),
        (
            "subnormal t_min",
            base.replace("t_min = 60.0", "t_min = 5e-324"),
        ),
        ("huge t_max", base.replace("t_max = 350.0", "t_max = 1e308")),
        (
            "huge anchors",
            base.replace(
                "anchor = [1.25, 1.25, 2.5]",
                "anchor = [1e300, 1e300, 1e300]",
            ),
        ),
        (
            "tiny participation",
            base.replace(
                "element = \"fem\"",
                "element = \"fem\"\nee_participation_min = 5e-324",
            ),
        ),
    ];
    for (what, t) in &cases {
        assert_ne!(t.as_str(), base, "{what}: replacement did not apply");
    }
    let texts: Vec<(String, String)> = cases.into_iter().map(|(a, b)| (a.to_string(), b)).collect();
    let failures = run_all(&texts);
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The fixed-size array keys of a scene text, as users name them in errors (`gravity`,
/// `end_effector.inertia`, `cables[3].anchor`, ...), with the line they are on.
fn array_keys(text: &str) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut section = String::new();
    let mut cable = None::<usize>;
    for (i, line) in text.split('\n').enumerate() {
        let t = line.trim();
        if t == "[[cables]]" {
            cable = Some(cable.map_or(0, |c| c + 1));
            section.clear();
        } else if t.starts_with('[') && t.ends_with(']') {
            section = t.trim_matches(['[', ']']).to_string();
        } else if let Some((key, value)) = t.split_once(" = ") {
            if value.starts_with('[') {
                let name = match (cable, section.is_empty()) {
                    (Some(c), true) => format!("cables[{c}].{key}"),
                    (_, false) => format!("{section}.{key}"),
                    (None, true) => key.to_string(),
                };
                out.push((name, i));
            }
        }
    }
    out
}

/// Bad forms of the array `value` (`[a, b, c]`, comments stripped) of `n` numbers, each with
/// the key suffix and message its error must carry.
fn bad_arrays(value: &str, n: usize) -> Vec<(String, String, String)> {
    let inner = &value[1..value.len() - 1];
    let items: Vec<&str> = inner.split(", ").collect();
    assert_eq!(items.len(), n, "{value}");
    let with = |j: usize, bad: &str| {
        let mut v = items.clone();
        v[j] = bad;
        format!("[{}]", v.join(", "))
    };
    let short = format!("[{}]", items[..n - 1].join(", "));
    vec![
        (
            format!("[{inner}, 12345, \"junk\", [1]]"),
            String::new(),
            format!("expected {n} numbers, got {}", n + 3),
        ),
        (
            format!("[{inner}, nan]"),
            String::new(),
            format!("expected {n} numbers, got {}", n + 1),
        ),
        (
            format!("[{inner}, {inner}]"),
            String::new(),
            format!("expected {n} numbers, got {}", 2 * n),
        ),
        (
            short,
            String::new(),
            format!("expected {n} numbers, got {}", n - 1),
        ),
        (
            "[]".into(),
            String::new(),
            format!("expected {n} numbers, got 0"),
        ),
        (
            "\"junk\"".into(),
            String::new(),
            format!("expected an array of {n} numbers, got a string"),
        ),
        (
            "1.0".into(),
            String::new(),
            format!("expected an array of {n} numbers, got a float"),
        ),
        (
            with(1, "\"2.0\""),
            "[1]".into(),
            "expected a number, got a string".into(),
        ),
        (
            with(n - 1, "true"),
            format!("[{}]", n - 1),
            "expected a number, got a boolean".into(),
        ),
        (
            with(0, "[1.0]"),
            "[0]".into(),
            "expected a number, got an array".into(),
        ),
        (
            with(0, "{ x = 1.0 }"),
            "[0]".into(),
            "expected a number, got a table".into(),
        ),
        (
            with(1, "1979-05-27"),
            "[1]".into(),
            "expected a number, got a datetime".into(),
        ),
    ]
}

/// Every fixed-size array key of the box scene (gravity, position, orientation, inertia and
/// its rows, every cable's anchor and attachment) made too long, too short, of mixed types,
/// NaN-trailing or not an array: refused, and the message names the file, the key (with the
/// cable index or the element) and what is wrong, on one line.
#[test]
fn every_array_key_has_exactly_its_length_of_numbers() {
    let text = BOX_SCENE_TOML;
    assert!(Scene::from_toml_str(text, FILE).is_ok());
    let lines: Vec<&str> = text.split('\n').collect();
    let keys = array_keys(text);
    let names: Vec<&str> = keys.iter().map(|(k, _)| k.as_str()).collect();
    for k in [
        "gravity",
        "end_effector.position",
        "end_effector.orientation",
        "end_effector.inertia",
        "cables[0].anchor",
        "cables[7].attachment",
    ] {
        assert!(names.contains(&k), "{k} not found in {names:?}");
    }
    let mut checked = 0;
    let mut failures = Vec::new();
    for (key, i) in &keys {
        let (lhs, rest) = lines[*i].split_once(" = ").unwrap();
        let value = rest.split('#').next().unwrap().trim();
        let mut cases: Vec<(String, String, String)> = Vec::new();
        if key == "end_effector.inertia" {
            let rows: Vec<&str> = value[1..value.len() - 1].split("], [").collect();
            let rows: Vec<String> = rows
                .iter()
                .map(|r| format!("[{}]", r.trim_matches(['[', ']'])))
                .collect();
            let all = rows.join(", ");
            cases.push((
                format!("[{all}, {}]", rows[2]),
                key.clone(),
                "expected 3 rows of 3 numbers, got 4".into(),
            ));
            cases.push((
                format!("[{}, {}]", rows[0], rows[1]),
                key.clone(),
                "expected 3 rows of 3 numbers, got 2".into(),
            ));
            cases.push((
                "[1.0, 2.0, 3.0]".into(),
                format!("{key}[0]"),
                "expected an array of 3 numbers, got a float".into(),
            ));
            for (bad, suffix, msg) in bad_arrays(&rows[1], 3) {
                let v = format!("[{}, {bad}, {}]", rows[0], rows[2]);
                cases.push((v, format!("{key}[1]{suffix}"), msg));
            }
        } else {
            let n = value.split(", ").count();
            for (bad, suffix, msg) in bad_arrays(value, n) {
                cases.push((bad, format!("{key}{suffix}"), msg));
            }
        }
        for (bad, err_key, msg) in cases {
            let mut v: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            v[*i] = format!("{lhs} = {bad}");
            let expected = format!("{FILE}: key `{err_key}`: {msg}");
            checked += 1;
            match Scene::from_toml_str(&v.join("\n"), FILE) {
                Ok(_) => failures.push(format!("{key} = {bad}: accepted")),
                Err(e) if e.to_string() != expected => {
                    failures.push(format!("{key} = {bad}: `{e}`, expected `{expected}`"))
                }
                Err(_) => {}
            }
        }
    }
    eprintln!("{checked} bad arrays checked over {} keys", keys.len());
    assert!(checked > 200, "only {checked} cases");
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// A NaN or infinity inside an array of the right length is refused by the key's own check.
#[test]
fn non_finite_array_elements_are_refused() {
    let text = BOX_SCENE_TOML;
    let lines: Vec<&str> = text.split('\n').collect();
    for (key, i) in array_keys(text) {
        let (lhs, rest) = lines[i].split_once(" = ").unwrap();
        let value = rest.split('#').next().unwrap().trim();
        for bad in ["nan", "inf", "-inf"] {
            // The first number of the value becomes `bad`.
            let start = value
                .find(|c: char| c.is_ascii_digit() || c == '-')
                .unwrap();
            let len = value[start..].find([',', ']']).unwrap();
            let v_bad = format!("{}{bad}{}", &value[..start], &value[start + len..]);
            let mut v: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            v[i] = format!("{lhs} = {v_bad}");
            let e = Scene::from_toml_str(&v.join("\n"), FILE)
                .err()
                .unwrap_or_else(|| panic!("{key} = {v_bad}: accepted"))
                .to_string();
            assert!(
                e.starts_with(&format!("{FILE}: key `{key}`: must be")) && !e.contains('\n'),
                "{key} = {v_bad}: {e}"
            );
        }
    }
}

proptest! {
    #![proptest_config(config(1024))]

    /// One to four random mutations of either shipped scene.
    #[test]
    fn mutated_scenes_never_panic(
        planar in any::<bool>(),
        muts in proptest::collection::vec(mutation(), 1..=4),
    ) {
        let mut text = if planar { PLANAR_SCENE_TOML } else { DEFAULT_SCENE_TOML }.to_string();
        for m in &muts {
            text = apply(&text, m);
        }
        check(&text)?;
    }

    /// Arbitrary printable text, and TOML-shaped text with random keys and values.
    #[test]
    fn random_text_never_panics(
        raw in "[ -~\n\t]{0,400}",
        keys in proptest::collection::vec(("[a-z_]{1,12}", 0..REPLACEMENTS.len()), 0..12),
    ) {
        check(&raw)?;
        let mut t = String::new();
        for (k, v) in &keys {
            t.push_str(&format!("{k} = {}\n", REPLACEMENTS[*v]));
        }
        check(&t)?;
    }

    /// Arbitrary bytes, decoded lossily (the parser takes &str).
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        check(&String::from_utf8_lossy(&bytes))?;
    }
}
