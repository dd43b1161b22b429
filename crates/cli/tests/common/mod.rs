//! What the program's tests share: fresh output folders and running `deferred`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `<test tmp>/<group>/<name>`, emptied (not created: the program makes its output folder).
pub fn out_folder(group: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(group)
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `deferred ARGS --out OUT`, without a backtrace setting of the caller's.
pub fn deferred(args: &[&str], out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_deferred"))
        .args(args)
        .arg("--out")
        .arg(out)
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("the deferred program runs")
}
