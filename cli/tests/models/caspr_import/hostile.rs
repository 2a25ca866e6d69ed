//! Hostile inputs: one-line errors naming the file (and line and element), no panics.

use super::{data, ipanema_opts, read, run, stderr};
use cablevib::caspr::{import_str, ImportOptions};
use cablevib::scene::Scene;
use nalgebra::Vector3;
use std::path::Path;

/// Importing `bodies` and `cables` (texts) with `opts` fails with one line containing
/// every one of `needles`.
fn refused(bodies: &str, cables: &str, opts: &ImportOptions, needles: &[&str]) {
    let e = import_str(bodies, "b.xml", cables, "c.xml", opts)
        .expect_err("must be refused")
        .to_string();
    assert_eq!(e.lines().count(), 1, "one line: {e}");
    // The library names its options by their fields, never by a command line's flags
    // (`--` then a letter; the XML parser's "expected '-->'" is no flag).
    let flag = e
        .match_indices("--")
        .any(|(i, _)| e[i + 2..].starts_with(|c: char| c.is_ascii_lowercase()));
    assert!(!flag, "a flag named: {e}");
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
}

/// The IPAnema test files and options.
fn ipanema_texts() -> (String, String, ImportOptions) {
    (
        read("ipanema1_bodies.xml"),
        read("ipanema1_cables.xml"),
        ipanema_opts(),
    )
}

#[test]
fn malformed_xml_and_unsupported_models_are_refused() {
    let (b, c, o) = ipanema_texts();
    refused(&first_half(&b), &c, &o, &["b.xml", "malformed XML"]);
    refused(&b, "<cables><cable_set", &o, &["c.xml", "malformed XML"]);
    // No entity is ever expanded: a DOCTYPE that can declare one is refused.
    refused(&laughs(), &c, &o, &["b.xml", "internal subset", "refused"]);
    let two = b.replace("</links>", &format!("{}</links>", link_block(&b)));
    refused(&two, &c, &o, &["b.xml", "2 moving links"]);
    let revolute = b.replace("SPATIAL_EULER_XYZ", "REVOLUTE_Z");
    refused(&revolute, &c, &o, &["b.xml:", "<joint>", "REVOLUTE_Z"]);
    let passive = c.replacen("cable_ideal", "cable_passive_linear_spring", 2);
    let needles = ["c.xml:", "cable_passive_linear_spring", "not supported"];
    refused(&b, &passive, &o, &needles);
    let base_twice = c.replacen("<link>1</link>", "<link>0</link>", 1);
    refused(
        &b,
        &base_twice,
        &o,
        &["c.xml:", "both attachments are on link 0"],
    );
    // Off-centre attachments with too few cables for a rigid platform.
    let needles = ["c.xml", "at least 6 cables", "has 4"];
    refused(&b, &four_cables(&c), &o, &needles);
    let nope = ImportOptions {
        cable_set: Some("nope".into()),
        ..o.clone()
    };
    let needles = ["c.xml", "no cable set `nope`", "original, springs"];
    refused(&b, &c, &nope, &needles);
}

#[test]
fn bad_numbers_and_missing_elements_name_file_line_and_element() {
    let (b, c, o) = ipanema_texts();
    let nan = c.replacen("-2.0 1.5 2.0", "-2.0 NaN 2.0", 1);
    let needles = ["c.xml:24:", "<location>", "`NaN` is not a finite number"];
    refused(&b, &nan, &o, &needles);
    let inf = b.replace("<mass>25.0</mass>", "<mass>inf</mass>");
    refused(&inf, &c, &o, &["b.xml:", "<mass>", "not a finite number"]);
    let word = b.replace("<Ixx>14.0</Ixx>", "<Ixx>heavy</Ixx>");
    refused(
        &word,
        &c,
        &o,
        &["b.xml:", "<Ixx>", "`heavy` is not a number"],
    );
    let two = c.replacen("-2.0 1.5 2.0", "-2.0 1.5", 1);
    refused(
        &b,
        &two,
        &o,
        &["c.xml:", "<location>", "expected 3 numbers"],
    );
    let no_ref = c.replacen(" attachment_reference=\"joint\"", "", 1);
    let needles = [
        "c.xml:",
        "<cable_ideal>",
        "missing attribute `attachment_reference`",
    ];
    refused(&b, &no_ref, &o, &needles);
    let no_max = c.replacen("<force_max>720.0</force_max>", "", 1);
    let needles = ["c.xml:", "<properties>", "missing <force_max>"];
    refused(&b, &no_max, &o, &needles);
    let no_com = b.replace("<com_location>0.0 0.0 0.0</com_location>", "");
    let needles = ["b.xml:", "<physical>", "missing <com_location>"];
    refused(&no_com, &c, &o, &needles);
}

#[test]
fn what_caspr_lacks_must_come_from_the_options() {
    let (b, c, o) = ipanema_texts();
    // CASPR's force_min of 0 without a T_min; cable_ideal without a Young's modulus.
    let slack = ImportOptions {
        t_min_n: None,
        ..o.clone()
    };
    let needles = ["c.xml", "`cable 1` … `cable 8`", "force_min ≤ 0", "t_min_n"];
    refused(&b, &c, &slack, &needles);
    let rigid = ImportOptions {
        youngs_modulus_pa: None,
        ..o.clone()
    };
    let needles = [
        "c.xml: ",
        "`cable 1` … `cable 8`",
        "cable_ideal",
        "youngs_modulus_pa",
    ];
    refused(&b, &c, &rigid, &needles);
    // Everything missing: every option named at once, in one line naming the file.
    let none = ImportOptions {
        weight_per_length_n_m: None,
        area_m2: None,
        youngs_modulus_pa: None,
        t_min_n: None,
        ..o.clone()
    };
    let needles = [
        "c.xml: ",
        "needs 4 more options",
        "weight_per_length_n_m",
        "area_m2",
        "youngs_modulus_pa",
        "t_min_n",
    ];
    refused(&b, &c, &none, &needles);
    let nan_area = ImportOptions {
        area_m2: Some(f64::NAN),
        ..o.clone()
    };
    refused(&b, &c, &nan_area, &["area", "NaN"]);
}

/// The first half of `s` (cut at a character boundary).
fn first_half(s: &str) -> String {
    let mut k = s.len() / 2;
    while !s.is_char_boundary(k) {
        k -= 1;
    }
    s[..k].to_string()
}

/// The `<link_rigid>` element of a bodies file (to make a second one).
fn link_block(b: &str) -> String {
    let start = b.find("<link_rigid").unwrap();
    let end = b.find("</link_rigid>").unwrap() + "</link_rigid>".len();
    b[start..end].replace("num=\"1\"", "num=\"2\"")
}

/// The IPAnema cables file with its default set cut to the first four cables.
fn four_cables(c: &str) -> String {
    let mut out = c.to_string();
    for k in 5..=8 {
        let open = format!("<cable_ideal name=\"cable {k}\"");
        let start = out.find(&open).unwrap();
        let end = start + out[start..].find("</cable_ideal>").unwrap() + "</cable_ideal>".len();
        out.replace_range(start..end, "");
    }
    out
}

/// Nested entities whose expansion would be 10⁹ characters.
fn laughs() -> String {
    let mut s = String::from("<?xml version=\"1.0\"?>\n<!DOCTYPE lolz [\n<!ENTITY l0 \"lol\">\n");
    for k in 1..=9 {
        let prev = format!("&l{};", k - 1).repeat(10);
        s += &format!("<!ENTITY l{k} \"{prev}\">\n");
    }
    s + "]>\n<links>&l9;</links>"
}

/// A flat expansion (no nesting for the parser's depth limit to catch): one `len`-byte
/// entity referenced `refs` times inside `<links>`, in an otherwise valid bodies file.
fn wide_entity(b: &str, len: usize, refs: usize) -> String {
    let decl = format!(
        "<!DOCTYPE bodies_system [\n<!ENTITY e \"{}\">\n]>\n",
        "x".repeat(len)
    );
    let start = b.find("<bodies_system").expect("root element");
    let s = decl + &b[start..];
    s.replacen("<links>", &format!("<links>{}", "&e;".repeat(refs)), 1)
}

#[test]
fn entity_declarations_are_refused_before_any_expansion() {
    let (b, c, o) = ipanema_texts();
    // 1 KiB × 4000 references: 4 MiB of expansion from a 13 kB file.
    let wide = wide_entity(&b, 1024, 4000);
    assert!(wide.len() < 20_000, "small file: {}", wide.len());
    refused(
        &wide,
        &c,
        &o,
        &["b.xml", "internal subset", "external DTD only"],
    );
    // In the cables file too, and after a comment and a processing instruction.
    let dtd = "<?xml version=\"1.0\"?>\n<!-- [ -->\n<?pi [ ?>\n\
               <!DOCTYPE cables SYSTEM \"a[b.dtd\" [ <!ENTITY e \"1\"> ]>\n";
    let start = c.find("<cables").expect("root element");
    let cables = format!("{dtd}{}", &c[start..]);
    refused(&b, &cables, &o, &["c.xml", "internal subset"]);
    // CASPR's own form (an external DTD, a `[` only inside its quoted name) is read.
    let external = format!("<!DOCTYPE cables SYSTEM \"../a[1].dtd\">\n{}", &c[start..]);
    import_str(&b, "b.xml", &external, "c.xml", &o).expect("external DTD is read");
}

#[test]
fn a_value_is_the_whole_text_of_its_element() {
    let (b, c, o) = ipanema_texts();
    let plain = import_str(&b, "b.xml", &c, "c.xml", &o).expect("plain");
    let split = b.replace("<mass>25.0</mass>", "<mass>2<!-- x -->5.0</mass>");
    let split = import_str(&split, "b.xml", &c, "c.xml", &o).expect("comment inside");
    let lead = b.replace("<mass>25.0</mass>", "<mass><!-- x -->25.0</mass>");
    let lead = import_str(&lead, "b.xml", &c, "c.xml", &o).expect("comment before");
    let cdata = b.replace("<mass>25.0</mass>", "<mass><![CDATA[2]]>5.0</mass>");
    let cdata = import_str(&cdata, "b.xml", &c, "c.xml", &o).expect("CDATA");
    // The test file's mass is 25.0 kg, read exactly.
    for s in [&plain, &split, &lead, &cdata] {
        assert_eq!(s.link.mass_kg, 25.0);
    }
    let nested = b.replace("<mass>25.0</mass>", "<mass>2<b/>5.0</mass>");
    refused(
        &nested,
        &c,
        &o,
        &["b.xml:", "<mass>", "may not contain elements", "<b>"],
    );
}

/// `import caspr` of the IPAnema test robot into `out`, without --t-min.
fn ipanema_cli(out: &Path, extra: &[&str]) -> std::process::Output {
    let (b, c) = (data("ipanema1_bodies.xml"), data("ipanema1_cables.xml"));
    let mut args = vec!["import", "caspr", b.to_str().unwrap(), c.to_str().unwrap()];
    args.extend_from_slice(&["--weight-per-length", "0.02", "--area", "1.767e-6"]);
    args.extend_from_slice(&["--youngs-modulus", "1e11", "-o", out.to_str().unwrap()]);
    args.extend_from_slice(extra);
    run(&args)
}

/// Exit code 1 and one line on stderr containing `needle`.
fn cli_refused(o: &std::process::Output, needle: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    assert!(e.contains(needle), "`{needle}` not in {e}");
}

#[test]
fn cli_errors_are_one_line() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_refused.toml");
    // force_min = 0 and no --t-min: refused, and no file written.
    let _ = std::fs::remove_file(&out);
    cli_refused(&ipanema_cli(&out, &[]), "--t-min");
    assert!(!out.exists());
    // The command line names its flags: every missing option at once, and the flag that
    // picks a cable set where the file has no default.
    let (b, c) = (data("ipanema1_bodies.xml"), data("ipanema1_cables.xml"));
    let (b, c) = (b.to_str().unwrap(), c.to_str().unwrap());
    let o = run(&["import", "caspr", b, c, "-o", out.to_str().unwrap()]);
    cli_refused(&o, "needs 4 more options: --weight-per-length (N/m");
    for flag in ["; --area (m²)", "; --youngs-modulus (Pa)", "; --t-min (N)"] {
        assert!(stderr(&o).contains(flag), "`{flag}` not in {}", stderr(&o));
    }
    let no_default = Path::new(env!("CARGO_TARGET_TMPDIR")).join("no_default_cables.xml");
    let text = read("ipanema1_cables.xml").replace(" default_cable_set=\"original\"", "");
    std::fs::write(&no_default, text).unwrap();
    let o = run(&[
        "import",
        "caspr",
        b,
        no_default.to_str().unwrap(),
        "--weight-per-length",
        "0.02",
        "--area",
        "1.767e-6",
        "--t-min",
        "10",
        "-o",
        out.to_str().unwrap(),
    ]);
    cli_refused(&o, "pick one with --cable-set (original, springs)");
    assert!(!out.exists());
    // Unknown set: the error lists the available ones.
    let o = ipanema_cli(&out, &["--t-min", "10", "--cable-set", "x"]);
    cli_refused(&o, "original, springs");
    // An unknown element is the parser's usage error (code 2), listing the values.
    let o = ipanema_cli(&out, &["--t-min", "10", "--element", "spline"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("possible values: fem, catenary, continuous, massless, auto"));
    // A missing file.
    let c = data("ipanema1_cables.xml");
    let o = run(&[
        "import",
        "caspr",
        "/nonexistent.xml",
        c.to_str().unwrap(),
        "--weight-per-length",
        "1",
        "--area",
        "1e-6",
        "-o",
        "/dev/null",
    ]);
    cli_refused(&o, "/nonexistent.xml");
}

#[test]
fn cli_position_moves_the_link_frame_and_the_result_analyzes() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_position.toml");
    let o = ipanema_cli(&out, &["--t-min", "10", "--position", "0.3,-0.2,1.1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = Scene::from_path(&out).unwrap();
    // The centre of mass is the link frame's origin in this model.
    assert_eq!(s.ee_position_m, Vector3::new(0.3, -0.2, 1.1));
    let o = run(&["analyze", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn names_with_quotes_and_newlines_cannot_break_the_scene_file() {
    // XML character references put a newline and quotes into the names; the scene's name
    // must stay one TOML string and the cable name one comment line.
    let b = read("ipanema1_bodies.xml")
        .replace("name=\"IPAnema 1\"", "name=\"x&#10;t_max = 1 # &quot;\\\"");
    let c = read("ipanema1_cables.xml").replace("name=\"cable 1\"", "name=\"c&#10;[[cables]]\"");
    let im = import_str(&b, "b.xml", &c, "c.xml", &ipanema_opts()).expect("imports");
    assert_eq!(im.scene.name, "x\nt_max = 1 # \"\\");
    assert_eq!(im.scene.n_cables(), 8);
}

#[test]
fn mutated_files_never_panic() {
    // Deterministic mutations (a 64-bit LCG, Knuth's constants): a character replaced by
    // one of XML's or a number's special characters, or the file cut short. Every result
    // must be an import or an error of one line; a panic fails the test.
    let (b, c, o) = ipanema_texts();
    let specials = [
        "<", ">", "\"", "&", "/", "0", "-", "e", ".", " ", "\u{0}", "NaN", "é",
    ];
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = |n: usize| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 33) as usize % n
    };
    let mut refused = 0;
    for round in 0..3000 {
        let target = if round % 2 == 0 { &b } else { &c };
        let mut at = next(target.len());
        while !target.is_char_boundary(at) {
            at -= 1;
        }
        let mutated = if round % 7 == 0 {
            target[..at].to_string()
        } else {
            let mut end = at + 1;
            while end < target.len() && !target.is_char_boundary(end) {
                end += 1;
            }
            let s = specials[next(specials.len())];
            format!("{}{s}{}", &target[..at], &target[end.min(target.len())..])
        };
        let (bb, cc) = if round % 2 == 0 {
            (mutated.as_str(), c.as_str())
        } else {
            (b.as_str(), mutated.as_str())
        };
        if let Err(e) = import_str(bb, "b.xml", cc, "c.xml", &o) {
            assert_eq!(e.to_string().lines().count(), 1, "{e}");
            refused += 1;
        }
    }
    // Most mutations hit a number, a tag or an attribute; the rest land in comments or
    // white space and import as before.
    assert!(refused > 0);
}

/// Cable-set ids, pulleys and huge numbers: each message says what is wrong, naming the
/// file, line and element, in one line of bounded length.
#[test]
fn set_ids_pulleys_and_huge_numbers_are_reported_clearly() {
    let (b, c, o) = ipanema_texts();
    // Sets without ids (CASPR selects sets by id): named, never "pick one with ( , )".
    let no_ids = c
        .replace(r#"<cable_set id="original">"#, "<cable_set>")
        .replace(r#"<cable_set id="springs">"#, "<cable_set>")
        .replace(r#" default_cable_set="original""#, "");
    let needles = ["c.xml:15: <cable_set>", "missing attribute `id`"];
    refused(&b, &no_ids, &o, &needles);
    // A duplicate id is refused, naming both lines (it once took the first silently).
    let twice = c.replace(
        r#"<cable_set id="springs">"#,
        r#"<cable_set id="original">"#,
    );
    let needles = ["c.xml:145: <cable_set>", "`original`", "line 15", "unique"];
    refused(&b, &twice, &o, &needles);
    // A pulley without its keys: named with its line and the missing key (not "1
    // attachments").
    let pulley = c.replacen(
        "<attachment>\n          <link>0</link>",
        "<base_rotating_pulley>\n          <link>0</link>",
        1,
    );
    assert_ne!(pulley, c, "the test must put a pulley in");
    let pulley = pulley.replacen("</attachment>", "</base_rotating_pulley>", 1);
    let needles = [
        "c.xml:",
        "<base_rotating_pulley>",
        "missing <fixed_location>",
    ];
    refused(&b, &pulley, &o, &needles);
    // A pulley type CASPR has but the import does not read: named, with the ones it reads.
    let other = pulley.replace("base_rotating_pulley", "winch_pulley");
    let needles = ["<winch_pulley>", "pulley type is not supported"];
    refused(&b, &other, &o, &needles);
    // Numbers from the file in messages: compact, not 309 digits.
    let huge = b.replace("<mass>25.0</mass>", "<mass>-1e308</mass>");
    let e = import_str(&huge, "b.xml", &c, "c.xml", &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("-1e308") && e.len() < 120, "{e}");
    let huge = c.replacen(
        "<force_max>720.0</force_max>",
        "<force_max>1e-300</force_max>",
        1,
    );
    let e = import_str(&b, "b.xml", &huge, "c.xml", &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("1e-300") && e.len() < 160, "{e}");
}

/// `import caspr` without the material flags: every missing flag in one line, naming the
/// cables file (clap once reported two, and the import then one more per run).
#[test]
fn cli_reports_every_missing_flag_at_once() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_missing.toml");
    let (b, c) = (data("ipanema1_bodies.xml"), data("ipanema1_cables.xml"));
    let args = ["import", "caspr", b.to_str().unwrap(), c.to_str().unwrap()];
    let o = run(&[&args[..], &["-o", out.to_str().unwrap()]].concat());
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    for flag in [
        "--weight-per-length",
        "--area",
        "--youngs-modulus",
        "--t-min",
    ] {
        assert!(e.contains(flag), "`{flag}` not in {e}");
    }
    assert!(e.contains("ipanema1_cables.xml"), "{e}");
}

/// A `screw_base_rotating_pulley` imports as a swivel pulley at its constant winch point
/// (the outlet's motion along the drum is the stated simplification), and the import says
/// in one line what it does not model; a negative pulley radius is refused, named.
#[test]
fn a_screw_pulley_imports_at_its_winch_point() {
    let (b, c, o) = ipanema_texts();
    let base = "<attachment>\n          <link>0</link>\n          <location>-2.0 1.5 2.0</location>\n        </attachment>";
    assert!(c.contains(base), "the first cable's base attachment");
    let screw = "<screw_base_rotating_pulley>\n          <constant_winch_point>-2.0 1.5 2.0</constant_winch_point>\n          <cable_pulley_entry_vector>0 0 2</cable_pulley_entry_vector>\n          <pulley_radius>0.03</pulley_radius>\n          <winch_vector>1 0 0</winch_vector>\n          <winch_radius>0.05</winch_radius>\n          <winch_groove_width>0.002</winch_groove_width>\n        </screw_base_rotating_pulley>";
    let im = import_str(&b, "b.xml", &c.replacen(base, screw, 1), "c.xml", &o).unwrap();
    let p = im.scene.cables[0].pulley.expect("cable 1 has its pulley");
    assert_eq!(p.radius_m, 0.03);
    assert_eq!(p.entry_unit, nalgebra::Vector3::z());
    assert_eq!(
        im.scene.cables[0].anchor_m,
        nalgebra::Vector3::new(-2.0, 1.5, 2.0)
    );
    assert!(im.scene.cables[1..].iter().all(|c| c.pulley.is_none()));
    let note = im.not_modelled().expect("a note");
    assert!(
        note.contains("screw") && note.lines().count() == 1,
        "{note}"
    );
    assert!(im.toml.contains("screw_base_rotating_pulley"));
    let bad = screw.replace("<pulley_radius>0.03", "<pulley_radius>-0.03");
    let needles = ["c.xml:", "<pulley_radius>", "must be >= 0"];
    refused(&b, &c.replacen(base, &bad, 1), &o, &needles);
}
