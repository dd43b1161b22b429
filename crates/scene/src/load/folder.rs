//! The files a scene names (glTF buffers and images, OBJ material libraries and textures),
//! read under the rule of the threat model in `docs/reliability.md`: a scene file is
//! untrusted, so it reads only regular files inside its own folder (after resolving `..` and
//! symbolic links), never more bytes than it declares or than a limit allows, and only through
//! relative paths (or `data:` URIs, which read no file).

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::SceneErrorKind;

/// The most bytes one referenced file may hold when the scene declares no length (images,
/// material libraries): 1 GiB.
pub(crate) const UNDECLARED_LIMIT: u64 = 1 << 30;

/// The canonical folder of a scene file; every file it names is read through it.
pub(crate) struct SceneFolder {
    root: PathBuf,
}

impl SceneFolder {
    /// The folder holding `scene_file`.
    pub(crate) fn of(scene_file: &Path) -> Result<Self, SceneErrorKind> {
        let parent = scene_file
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        Ok(Self {
            root: parent.canonicalize()?,
        })
    }

    /// Reads `path` as written in an OBJ or MTL file (a relative file path, not a URI), at
    /// most `limit` bytes.
    pub(crate) fn read_path(&self, path: &str, limit: u64) -> Result<Vec<u8>, SceneErrorKind> {
        self.read(path, path, limit)
    }

    /// Reads a glTF URI (RFC 3986, percent-encoded): a relative reference inside the folder
    /// or a `data:` URI; at most `limit` bytes.
    pub(crate) fn read_uri(&self, uri: &str, limit: u64) -> Result<Vec<u8>, SceneErrorKind> {
        if let Some(data) = uri.strip_prefix("data:") {
            return decode_data_uri(uri, data, limit);
        }
        let decoded = urlencoding::decode(uri).map_err(|_| SceneErrorKind::Reference {
            reference: uri.into(),
            problem: "its percent-decoding is not UTF-8".into(),
        })?;
        self.read(uri, &decoded, limit)
    }

    fn read(&self, reference: &str, path: &str, limit: u64) -> Result<Vec<u8>, SceneErrorKind> {
        let refuse = |problem: &str| SceneErrorKind::Reference {
            reference: reference.into(),
            problem: problem.into(),
        };
        if has_scheme(path) {
            return Err(refuse(
                "only relative paths inside the scene's folder and data: URIs are read",
            ));
        }
        let relative = Path::new(path);
        if path.is_empty() || relative.is_absolute() || path.starts_with(['/', '\\']) {
            return Err(refuse(
                "absolute paths are not read (a scene reads only inside its folder)",
            ));
        }
        // `..` that climbs above the folder is refused before the file system is asked, so
        // nothing outside (not even whether a file exists there) is looked at.
        let mut depth = 0i64;
        for c in relative.components() {
            depth += match c {
                std::path::Component::Normal(_) => 1,
                std::path::Component::ParentDir => -1,
                _ => 0,
            };
            if depth < 0 {
                return Err(refuse("it resolves outside the scene's folder"));
            }
        }
        let resolved = self
            .root
            .join(relative)
            .canonicalize()
            .map_err(|e| match e.kind() {
                std::io::ErrorKind::NotFound => SceneErrorKind::MissingFile(reference.into()),
                _ => refuse(&e.to_string()),
            })?;
        if !resolved.starts_with(&self.root) {
            return Err(refuse("it resolves outside the scene's folder"));
        }
        let file = std::fs::File::open(&resolved)?;
        let meta = file.metadata()?;
        if !meta.is_file() {
            return Err(refuse("not a regular file"));
        }
        if meta.len() > limit {
            return Err(refuse(&format!(
                "holds {} bytes, more than the {limit} allowed",
                meta.len()
            )));
        }
        // The length was checked, but a file may grow while read: never take more.
        let mut bytes = Vec::with_capacity(meta.len() as usize);
        file.take(limit).read_to_end(&mut bytes)?;
        Ok(bytes)
    }
}

/// `true` when `path` starts with a URI scheme (`file:`, `http:`, `C:` …).
fn has_scheme(path: &str) -> bool {
    match path.split_once(':') {
        Some((scheme, _)) => {
            !scheme.is_empty()
                && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
                && scheme
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
        }
        None => false,
    }
}

/// The bytes of a `data:[<media type>][;base64],<data>` URI (glTF embeds buffers and images
/// this way), at most `limit`.
fn decode_data_uri(uri: &str, data: &str, limit: u64) -> Result<Vec<u8>, SceneErrorKind> {
    let refuse = |problem: String| SceneErrorKind::Reference {
        reference: uri.chars().take(48).collect(),
        problem,
    };
    let (header, payload) = data
        .split_once(',')
        .ok_or_else(|| refuse("a data: URI without a comma".into()))?;
    let bytes = if header.ends_with(";base64") {
        if payload.len() as u64 / 4 * 3 > limit {
            return Err(refuse(format!("holds more than the {limit} bytes allowed")));
        }
        base64::decode(payload).map_err(|e| refuse(format!("bad base64: {e}")))?
    } else {
        urlencoding::decode_binary(payload.as_bytes()).into_owned()
    };
    if bytes.len() as u64 > limit {
        return Err(refuse(format!(
            "holds {} bytes, more than the {limit} allowed",
            bytes.len()
        )));
    }
    Ok(bytes)
}
