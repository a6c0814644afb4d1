//! Output paths never destroy: an output that names an input (or another
//! output) is refused before any work, a symbolic link is written through to
//! its target and stays a link, a directory or device is refused, and a
//! failed write leaves no temporary file. Inputs are written by the tests.

use crate::support::{odocal, scratch};
use std::path::{Path, PathBuf};
use std::process::Output;

const BUNDLED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/scans/wheelchair-corridor.mcap"
);

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A short copy of the bundled bag, as a user's own input file.
fn input_bag(d: &Path) -> PathBuf {
    let bag = d.join("victim.mcap");
    std::fs::copy(BUNDLED, &bag).unwrap();
    bag
}

/// No `.NAME.tmp-PID` file left in `dir`.
fn no_temps(dir: &Path) {
    let temps: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(temps.is_empty(), "temporary files left: {temps:?}");
}

#[test]
fn an_output_naming_the_input_is_refused_and_the_input_kept() {
    let d = scratch("outputs_input");
    let bag = input_bag(&d);
    let before = std::fs::read(&bag).unwrap();
    let b = bag.to_str().unwrap();
    // The same path, and the same file through a link and through "..".
    let link = d.join("link.mcap");
    std::os::unix::fs::symlink(&bag, &link).unwrap();
    let dotted = d.join("sub").join("..").join("victim.mcap");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    for out in [bag.clone(), link.clone(), dotted] {
        let o = odocal(&["icp", "--input", b, "--out", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains("is the input"), "{}", stderr(&o));
        assert!(stderr(&o).contains("victim.mcap"), "{}", stderr(&o));
    }
    let o = odocal(&[
        "icp",
        "--input",
        b,
        "--out",
        d.join("t.tum").to_str().unwrap(),
        "--motions",
        b,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // Two outputs of one run that are the same file.
    let o = odocal(&[
        "simulate",
        "--duration",
        "1",
        "--out",
        d.join("s.mcap").to_str().unwrap(),
        "--truth",
        d.join("s.mcap").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("is the output"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(&bag).unwrap(),
        before,
        "the input is untouched"
    );
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    no_temps(&d);
}

#[test]
fn a_symlinked_output_is_written_through_and_stays_a_link() {
    let d = scratch("outputs_symlink");
    let bag = input_bag(&d);
    let target = d.join("real.tum");
    std::fs::write(&target, "stale\n").unwrap();
    let link = d.join("out.tum");
    std::os::unix::fs::symlink("real.tum", &link).unwrap();
    let o = odocal(&[
        "icp",
        "--input",
        bag.to_str().unwrap(),
        "--out",
        link.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    let text = std::fs::read_to_string(&target).unwrap();
    assert!(
        text.starts_with("# timestamp"),
        "the target holds the trajectory"
    );
    assert!(text.lines().count() > 1000);
    no_temps(&d);
}

#[test]
fn a_device_or_directory_as_output_is_refused_untouched() {
    let d = scratch("outputs_special");
    let bag = input_bag(&d);
    let b = bag.to_str().unwrap();
    let o = odocal(&["icp", "--input", b, "--out", "/dev/null"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("/dev/null"), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a regular file"), "{}", stderr(&o));
    use std::os::unix::fs::FileTypeExt;
    let null = std::fs::symlink_metadata("/dev/null").unwrap();
    assert!(
        null.file_type().is_char_device(),
        "/dev/null is still a device"
    );
    // An existing directory where a file goes: refused, nothing left behind.
    let dir = d.join("taken.tum");
    std::fs::create_dir_all(&dir).unwrap();
    let o = odocal(&["icp", "--input", b, "--out", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(dir.is_dir());
    let cal = d.join("cal");
    std::fs::create_dir_all(cal.join("summary.json")).unwrap();
    let o = odocal(&[
        "calibrate",
        "--input",
        b,
        "--method",
        "none",
        "--out",
        cal.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        !cal.join("calibration.csv").exists(),
        "refused before any work"
    );
    no_temps(&d);
    no_temps(&cal);
}

#[test]
fn a_write_that_fails_at_the_rename_leaves_no_temporary_file() {
    // The library's writers alone: the target turns into a directory between
    // the start of the write and its commit.
    let d = scratch("outputs_rename_fails");
    let p = d.join("rows.csv");
    let mut w = odocal::io::stream_out::AtomicWriter::create(&p).unwrap();
    std::io::Write::write_all(w.writer(), b"a,b\n").unwrap();
    std::fs::create_dir_all(p.join("inside")).unwrap();
    assert!(w.commit().is_err());
    no_temps(&d);
    let q = d.join("whole.txt");
    std::fs::create_dir_all(q.join("inside")).unwrap();
    assert!(odocal::io::atomic::write_bytes_atomic(&q, b"x").is_err());
    no_temps(&d);
}
