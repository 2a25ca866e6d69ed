use super::*;
use crate::input_file::test_files::temp_dir;

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn a_file_is_written_whole_and_replaces_the_target_keeping_its_mode() {
    let d = temp_dir("out-whole");
    let p = d.join("a.csv");
    write_whole(&p, b"one\n").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"one\n");
    std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o640)).unwrap();
    write_whole(&p, b"two\n").unwrap();
    assert_eq!(std::fs::read(&p).unwrap(), b"two\n");
    let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o7777;
    assert_eq!(mode, 0o640);
    assert_eq!(names(&d), ["a.csv"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_uncommitted_file_leaves_the_target_untouched_and_no_temporary_file() {
    let d = temp_dir("out-drop");
    let p = d.join("a.csv");
    std::fs::write(&p, "before\n").unwrap();
    let mut f = OutputFile::create(&p).unwrap();
    f.write_all(&vec![b'x'; 1 << 20]).unwrap();
    let temp = f.temp_path().unwrap().to_path_buf();
    assert!(temp.exists());
    assert!(
        temp.file_name()
            .unwrap()
            .to_string_lossy()
            .ends_with(".part"),
        "{temp:?}"
    );
    assert_eq!(std::fs::read(&p).unwrap(), b"before\n");
    drop(f);
    assert_eq!(std::fs::read(&p).unwrap(), b"before\n");
    assert_eq!(names(&d), ["a.csv"]);
    // A panic while writing unwinds through the same drop.
    let p2 = p.clone();
    let r = std::panic::catch_unwind(move || {
        let mut f = OutputFile::create(&p2).unwrap();
        f.write_all(b"half").unwrap();
        panic!("mid-write");
    });
    assert!(r.is_err());
    assert_eq!(std::fs::read(&p).unwrap(), b"before\n");
    assert_eq!(names(&d), ["a.csv"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_symbolic_link_is_written_through_and_kept() {
    let d = temp_dir("out-link");
    let real = d.join("real.csv");
    std::fs::write(&real, "old").unwrap();
    let link = d.join("link.csv");
    std::os::unix::fs::symlink("real.csv", &link).unwrap();
    write_whole(&link, b"new").unwrap();
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(std::fs::read(&real).unwrap(), b"new");
    assert_eq!(names(&d), ["link.csv", "real.csv"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn devices_are_written_in_place_and_directories_refused() {
    write_whole(Path::new("/dev/null"), b"gone").unwrap();
    let d = temp_dir("out-dir");
    let e = write_whole(&d, b"x").unwrap_err();
    assert!(
        matches!(
            e,
            OutputFileError::NotWritable {
                kind: "directory",
                ..
            }
        ),
        "{e}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_new_file_never_replaces_one_that_exists_or_appears() {
    let d = temp_dir("out-new");
    let p = d.join("run.mcap");
    std::fs::write(&p, "kept").unwrap();
    let e = OutputFile::create_new(&p).unwrap_err();
    assert!(matches!(e, OutputFileError::Exists { .. }), "{e}");
    std::fs::remove_file(&p).unwrap();
    let mut f = OutputFile::create_new(&p).unwrap();
    f.write_all(b"recording").unwrap();
    std::fs::write(&p, "appeared").unwrap();
    let e = f.commit().unwrap_err();
    assert!(matches!(e, OutputFileError::Exists { .. }), "{e}");
    assert_eq!(std::fs::read(&p).unwrap(), b"appeared");
    assert_eq!(names(&d), ["run.mcap"]);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn an_output_that_is_an_input_is_refused_by_identity() {
    let d = temp_dir("out-identity");
    let input = d.join("big.csv");
    std::fs::write(&input, "t,x,y,z\n").unwrap();
    let hard = d.join("hard.csv");
    std::fs::hard_link(&input, &hard).unwrap();
    let soft = d.join("soft.csv");
    std::os::unix::fs::symlink(&input, &soft).unwrap();
    let dotted = d.join(".").join("big.csv");
    for out in [&input, &hard, &soft, &dotted] {
        let e = refuse_inputs(&[out], &[&input]).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, OutputFileError::IsInput { .. }), "{msg}");
        assert!(
            msg.contains(&out.display().to_string())
                && msg.contains(&input.display().to_string())
                && !msg.contains('\n'),
            "{msg}"
        );
    }
    let other = d.join("other.csv");
    refuse_inputs(&[&other], &[&input, &d.join("missing.toml")]).unwrap();
    // Two outputs that are one file, existing or not.
    let e = refuse_inputs(&[&other, &d.join("x/../other.csv")], &[&input]).unwrap_err();
    assert!(matches!(e, OutputFileError::SameOutput { .. }), "{e}");
    let e = refuse_inputs(&[&input, &hard], &[] as &[&Path]).unwrap_err();
    assert!(matches!(e, OutputFileError::SameOutput { .. }), "{e}");
    assert_eq!(std::fs::read(&input).unwrap(), b"t,x,y,z\n");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn scratch_files_are_removed_when_dropped() {
    let d = temp_dir("out-scratch");
    let target = d.join("t.csv");
    let s = ScratchFile::create_beside(&target).unwrap();
    let p = s.path().to_path_buf();
    let mut f: &File = s.file();
    f.write_all(b"spill").unwrap();
    assert!(p.exists());
    drop(s);
    assert!(names(&d).is_empty());
    std::fs::remove_dir_all(&d).unwrap();
}
