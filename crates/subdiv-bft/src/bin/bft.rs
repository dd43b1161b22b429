//! Builds the Loop basis-function tables and writes their versioned binary file
//! (`cargo xtask bft [--level L] [--max-valence N] [-o FILE]`).

use std::time::Instant;

use subdiv_bft::{BftSet, DEFAULT_LEVEL, MAX_VALENCE};

fn main() {
    if let Err(e) = run() {
        eprintln!("bft: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let mut level = DEFAULT_LEVEL;
    let mut valence = MAX_VALENCE;
    let mut out = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--level" => level = value()?.parse().map_err(|e| format!("--level: {e}"))?,
            "--max-valence" => {
                valence = value()?
                    .parse()
                    .map_err(|e| format!("--max-valence: {e}"))?
            }
            "-o" | "--out" => out = Some(std::path::PathBuf::from(value()?)),
            _ => {
                return Err(format!(
                    "unknown argument {a}; usage: bft [--level L] [--max-valence N] [-o FILE]"
                ));
            }
        }
    }
    let path = out.unwrap_or_else(|| BftSet::default_path(level, valence));
    let t = Instant::now();
    let set = BftSet::build(level, valence).map_err(|e| e.to_string())?;
    let built = t.elapsed();
    let bytes = set.to_bytes();
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    std::fs::write(&path, &bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    println!(
        "{}: {} tables (level {level}, {}×{} segments, valence ≤ {valence}, interior and boundary), {:.2} MB, built in {:.2} s",
        path.display(),
        set.tables.len(),
        set.segments(),
        set.segments(),
        bytes.len() as f64 / 1e6,
        built.as_secs_f64()
    );
    Ok(())
}
