//! Image files are written atomically: a failed write names the path and leaves nothing
//! behind, a symbolic link at the output path is replaced rather than written through.

use gbuffer::Image;

fn folder(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("atomic")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("folder");
    dir
}

fn entries(dir: &std::path::Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn writes_replace_the_file_and_leave_no_temporary() {
    let dir = folder("replace");
    let image = Image::from_vec(2, 1, vec![[1.0, 0.0, 0.0, 1.0]; 2]).expect("image");
    for _ in 0..2 {
        image.write_png(&dir.join("render.png")).expect("png");
        image.write_exr(&dir.join("render.exr")).expect("exr");
    }
    assert_eq!(entries(&dir), ["render.exr", "render.png"]);
    let png = std::fs::read(dir.join("render.png")).expect("read");
    assert_eq!(&png[1..4], b"PNG");
}

#[test]
fn a_failed_write_names_the_path_and_leaves_nothing() {
    let dir = folder("fail");
    let image = Image::from_vec(1, 1, vec![[0.5; 4]]).expect("image");
    // The output path is a folder: the rename fails after the temporary was written.
    std::fs::create_dir(dir.join("render.png")).expect("folder in the way");
    let e = image
        .write_png(&dir.join("render.png"))
        .expect_err("cannot replace a folder");
    assert!(e.to_string().contains("render.png"), "{e}");
    assert_eq!(entries(&dir), ["render.png"]);
    let missing = dir.join("no/such/folder/render.exr");
    let e = image.write_exr(&missing).expect_err("no folder");
    assert!(e.to_string().contains("no/such/folder/render.exr"), "{e}");
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_at_the_output_is_replaced_not_followed() {
    let dir = folder("link");
    std::fs::write(dir.join("precious.txt"), "keep me").expect("file");
    std::os::unix::fs::symlink(dir.join("precious.txt"), dir.join("render.png")).expect("link");
    let image = Image::from_vec(1, 1, vec![[0.5; 4]]).expect("image");
    image.write_png(&dir.join("render.png")).expect("png");
    assert_eq!(
        std::fs::read_to_string(dir.join("precious.txt")).expect("read"),
        "keep me"
    );
    let meta = std::fs::symlink_metadata(dir.join("render.png")).expect("meta");
    assert!(meta.is_file(), "the link was written through");
}

#[test]
fn accuracy_measures_relative_luminance_error_and_bias() {
    let img = |v: &[[f32; 4]]| Image::from_vec(5, 1, v.to_vec()).expect("5×1");
    let g = [0.5, 0.5, 0.5, 1.0];
    let truth = img(&[g, g, [0.0; 4], g, [100.0, 100.0, 100.0, 1.0]]);
    let same = gbuffer::accuracy(&truth, &truth, 10.0);
    assert_eq!((same.error, same.bias, same.pixels), (0.0, 0.0, 2));
    // Twice as bright on the two counted pixels (the black pixel, the emitter and its
    // neighbour are skipped).
    let double = img(&[[1.0, 1.0, 1.0, 1.0]; 5]);
    let a = gbuffer::accuracy(&truth, &double, 10.0);
    assert!(
        (a.error - 1.0).abs() < 1e-6 && (a.bias - 1.0).abs() < 1e-6,
        "{a:?}"
    );
    // NaN is an error, not a skipped pixel.
    let nan = img(&[[f32::NAN; 4], g, g, g, g]);
    let a = gbuffer::accuracy(&truth, &nan, 10.0);
    assert!((a.error - 0.5).abs() < 1e-6, "{a:?}");
}
