//! WGSL libraries: each crate carries its own shaders and names the libraries it imports.
//!
//! A crate's WGSL lives in `shaders/<crate>/` at the workspace root (the single source) and is
//! reached from the crate through its `shaders` link, so `cargo package` carries it. The crate
//! declares its files once with [`shader_library!`](crate::shader_library):
//!
//! ```ignore
//! pub static SHADERS: gpu::shader::Library =
//!     gpu::shader_library!("interleave", imports: [gbuffer::SHADERS], files: ["blur.wgsl"]);
//! ```
//!
//! WGSL has no include mechanism; a file may start with lines of the form
//! `// #import gbuffer/normal_encoding.wgsl`, and [`Library::source`] prepends those files
//! (recursively, each once) from this library or one it imports.
//!
//! **Specialisation** is the one compile-time mechanism for what `override` constants cannot
//! express (types, storage formats, array sizes): a [`Specialisation`] replaces the value of
//! named module-scope `const NAME: T = …;` or `alias NAME = …;` declarations. The files stay
//! valid WGSL as written (their default variant); every variant a crate can build is listed
//! by that crate and validated by naga in its no-GPU shader test ([`Library::validate`]).

use crate::GpuError;

/// The WGSL files of one crate, and the libraries their `#import`s may name.
#[derive(Debug)]
pub struct Library {
    /// The crate's shader folder name, the first part of an import path (`gbuffer`).
    pub name: &'static str,
    /// File name (relative to the crate's `shaders/`) and source.
    pub files: &'static [(&'static str, &'static str)],
    /// Libraries whose files this one imports.
    pub imports: &'static [&'static Library],
}

/// Declares a crate's [`Library`]: its name, the libraries it imports and its files, embedded
/// from `<crate>/shaders/`.
#[macro_export]
macro_rules! shader_library {
    ($name:literal, imports: [$($import:expr),* $(,)?], files: [$($file:literal),* $(,)?] $(,)?) => {
        $crate::shader::Library {
            name: $name,
            files: &[$((
                $file,
                include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/shaders/", $file)),
            )),*],
            imports: &[$(&$import),*],
        }
    };
}

impl Library {
    /// `<library>/<file>` for every file.
    pub fn paths(&self) -> impl Iterator<Item = String> + '_ {
        self.files.iter().map(|(f, _)| format!("{}/{f}", self.name))
    }

    /// The library named `name`: this one or one it imports, transitively.
    fn find(&self, name: &str) -> Option<&Library> {
        if self.name == name {
            return Some(self);
        }
        self.imports.iter().find_map(|l| l.find(name))
    }

    fn raw(&self, path: &str) -> Result<&'static str, GpuError> {
        let missing = |message: &str| GpuError::Shader {
            name: path.into(),
            message: message.into(),
        };
        let (lib, file) = path
            .split_once('/')
            .ok_or_else(|| missing("an import path is <library>/<file>"))?;
        let lib = self
            .find(lib)
            .ok_or_else(|| missing(&format!("library {lib} is not imported by {}", self.name)))?;
        lib.files
            .iter()
            .find(|(f, _)| *f == file)
            .map(|(_, src)| *src)
            .ok_or_else(|| missing(&format!("no such file in library {}", lib.name)))
    }

    /// The source of `file` (of this library) with its `#import`s resolved; its `enable`
    /// directives (e.g. `enable wgpu_binding_array;`) moved to the top, where WGSL wants them.
    pub fn source(&self, file: &str) -> Result<String, GpuError> {
        let mut seen = Vec::new();
        let mut out = String::new();
        self.resolve(&format!("{}/{file}", self.name), &mut seen, &mut out)?;
        let (directives, rest): (Vec<&str>, Vec<&str>) = out
            .lines()
            .partition(|line| line.starts_with("enable ") && line.trim_end().ends_with(';'));
        if directives.is_empty() {
            return Ok(out);
        }
        Ok(directives
            .into_iter()
            .chain(rest)
            .collect::<Vec<_>>()
            .join("\n")
            + "\n")
    }

    fn resolve(
        &self,
        path: &str,
        seen: &mut Vec<String>,
        out: &mut String,
    ) -> Result<(), GpuError> {
        if seen.iter().any(|s| s == path) {
            return Ok(());
        }
        seen.push(path.to_owned());
        let src = self.raw(path)?;
        for line in src.lines() {
            if let Some(dep) = line.trim().strip_prefix("// #import ") {
                self.resolve(dep.trim(), seen, out)?;
            }
        }
        out.push_str(&format!("// ---- {path}\n"));
        out.push_str(src);
        out.push('\n');
        Ok(())
    }

    /// The source of `file` with imports resolved and `specialisation` applied.
    pub fn specialised(
        &self,
        file: &str,
        specialisation: &Specialisation,
    ) -> Result<String, GpuError> {
        specialisation.apply(&format!("{}/{file}", self.name), self.source(file)?)
    }

    /// Compiles `file` (default variant) into a module.
    pub fn module(
        &self,
        device: &wgpu::Device,
        file: &str,
    ) -> Result<wgpu::ShaderModule, GpuError> {
        self.module_with(device, file, &Specialisation::default())
    }

    /// Compiles `file` with `specialisation` applied into a module.
    pub fn module_with(
        &self,
        device: &wgpu::Device,
        file: &str,
        specialisation: &Specialisation,
    ) -> Result<wgpu::ShaderModule, GpuError> {
        let src = self.specialised(file, specialisation)?;
        Ok(device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&format!("{}/{file}", self.name)),
            source: wgpu::ShaderSource::Wgsl(src.into()),
        }))
    }

    /// Parses and validates `file` under `specialisation` with naga (all validation flags, all
    /// capabilities): what every crate's no-GPU shader test runs over its variants.
    pub fn validate(&self, file: &str, specialisation: &Specialisation) -> Result<(), String> {
        let label = format!("{}/{file} {specialisation}", self.name);
        let src = self
            .specialised(file, specialisation)
            .map_err(|e| format!("{label}: {e}"))?;
        let module = naga::front::wgsl::parse_str(&src)
            .map_err(|e| format!("{label}: parse: {}", e.emit_to_string(&src)))?;
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .map_err(|e| format!("{label}: validate: {}", e.emit_to_string(&src)))?;
        Ok(())
    }

    /// Validates every listed variant, and every file without a listed variant in its default
    /// variant (a file with listed variants is built only as those: its defaults may not
    /// compile alone, e.g. bind-group numbers its variants move); returns all failures. Also
    /// fails for a `.wgsl` file in `folder` that the library does not declare.
    pub fn validate_all(
        &self,
        folder: &std::path::Path,
        variants: &[(&str, Specialisation)],
    ) -> Vec<String> {
        let mut failures: Vec<String> = self
            .files
            .iter()
            .filter(|(f, _)| !variants.iter().any(|(v, _)| v == f))
            .map(|(f, _)| (*f, Specialisation::default()))
            .chain(variants.iter().map(|(f, s)| (*f, s.clone())))
            .filter_map(|(f, s)| self.validate(f, &s).err())
            .collect();
        match std::fs::read_dir(folder) {
            Err(e) => failures.push(format!("{}: {e}", folder.display())),
            Ok(entries) => {
                for e in entries.flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if name.ends_with(".wgsl") && !self.files.iter().any(|(f, _)| *f == name) {
                        failures.push(format!(
                            "{}/{name} is not declared in the library",
                            self.name
                        ));
                    }
                }
            }
        }
        failures
    }
}

/// Values for named module-scope `const` and `alias` declarations of a shader.
///
/// ```
/// let s = gpu::shader::Specialisation::default().set("TILE", "32u");
/// let src = s.apply("k.wgsl", "const TILE: u32 = 16u;\n".into()).unwrap();
/// assert_eq!(src, "const TILE: u32 = 32u;\n");
/// ```
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Specialisation(Vec<(String, String)>);

impl Specialisation {
    /// This specialisation with `name` declared as `value` (WGSL text: `32u`, `vec4<f32>`).
    pub fn set(mut self, name: &str, value: impl std::fmt::Display) -> Self {
        self.0.retain(|(n, _)| n != name);
        self.0.push((name.to_owned(), value.to_string()));
        self
    }

    /// `src` with each named declaration's value replaced. Each name must be declared exactly
    /// once, as `const NAME: T = …;`, `const NAME = …;` or `alias NAME = …;` on one line.
    pub fn apply(&self, label: &str, src: String) -> Result<String, GpuError> {
        let mut lines: Vec<String> = src.lines().map(str::to_owned).collect();
        for (name, value) in &self.0 {
            let declares = |line: &str| {
                let line = line.trim_start();
                let rest = line
                    .strip_prefix("const ")
                    .or_else(|| line.strip_prefix("alias "));
                rest.and_then(|r| r.strip_prefix(name.as_str()))
                    .is_some_and(|r| r.trim_start().starts_with([':', '=']))
            };
            let found: Vec<usize> = (0..lines.len()).filter(|&i| declares(&lines[i])).collect();
            let [i] = found[..] else {
                return Err(GpuError::Shader {
                    name: label.into(),
                    message: format!(
                        "specialisation of {name}: {} one-line `const`/`alias` declarations found, one expected",
                        found.len()
                    ),
                });
            };
            let line = &lines[i];
            let (Some(eq), Some(end)) = (line.find('='), line.rfind(';')) else {
                return Err(GpuError::Shader {
                    name: label.into(),
                    message: format!("specialisation of {name}: `{line}` has no `= …;`"),
                });
            };
            lines[i] = format!("{} {value}{}", &line[..=eq], &line[end..]);
        }
        let mut out = lines.join("\n");
        if src.ends_with('\n') {
            out.push('\n');
        }
        Ok(out)
    }
}

impl std::fmt::Display for Specialisation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self.0.iter().map(|(n, v)| format!("{n}={v}")).collect();
        write!(f, "[{}]", parts.join(", "))
    }
}

/// Panics listing every failure of [`Library::validate_all`] over the crate's `shaders/`
/// folder (`<manifest dir>/shaders`): the body of each crate's no-GPU shader test.
pub fn assert_valid(library: &Library, manifest_dir: &str, variants: &[(&str, Specialisation)]) {
    let folder = std::path::Path::new(manifest_dir).join("shaders");
    let failures = library.validate_all(&folder, variants);
    assert!(
        failures.is_empty(),
        "invalid shaders:\n{}",
        failures.join("\n")
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    static BASE: Library = Library {
        name: "base",
        files: &[("common.wgsl", "const N: u32 = 4u;\nalias T = vec4<f32>;\n")],
        imports: &[],
    };
    static TOP: Library = Library {
        name: "top",
        files: &[(
            "k.wgsl",
            "// #import base/common.wgsl\n@compute @workgroup_size(1) fn main() { var x = array<T, N>(); }\n",
        )],
        imports: &[&BASE],
    };

    #[test]
    fn imports_resolve_across_libraries_and_validate() {
        let src = TOP.source("k.wgsl").unwrap();
        assert!(src.find("const N").unwrap() < src.find("fn main").unwrap());
        TOP.validate("k.wgsl", &Specialisation::default()).unwrap();
    }

    #[test]
    fn enable_directives_move_above_their_imports() {
        static ENABLING: Library = Library {
            name: "enabling",
            files: &[(
                "e.wgsl",
                "enable wgpu_binding_array;\n// #import base/common.wgsl\n@group(0) @binding(0) var t: binding_array<texture_2d<f32>>;\n@compute @workgroup_size(1) fn main() { let d = textureDimensions(t[N]); }\n",
            )],
            imports: &[&BASE],
        };
        let src = ENABLING.source("e.wgsl").unwrap();
        assert!(src.starts_with("enable wgpu_binding_array;\n"), "{src}");
        assert_eq!(src.matches("enable ").count(), 1);
        ENABLING
            .validate("e.wgsl", &Specialisation::default())
            .unwrap();
        // Without the move the directive would follow the import, which WGSL refuses.
        assert!(
            TOP.source("k.wgsl")
                .unwrap()
                .starts_with("// ---- base/common.wgsl")
        );
    }

    #[test]
    fn specialisation_rewrites_const_and_alias() {
        let s = Specialisation::default()
            .set("N", "8u")
            .set("T", "vec4<u32>");
        let src = TOP.specialised("k.wgsl", &s).unwrap();
        assert!(src.contains("const N: u32 = 8u;"));
        assert!(src.contains("alias T = vec4<u32>;"));
        TOP.validate("k.wgsl", &s).unwrap();
        // An invalid value is caught by validation.
        let bad = Specialisation::default().set("N", "0u");
        assert!(TOP.validate("k.wgsl", &bad).is_err());
    }

    #[test]
    fn unknown_names_and_files_are_errors() {
        let s = Specialisation::default().set("MISSING", "1u");
        assert!(
            TOP.specialised("k.wgsl", &s)
                .unwrap_err()
                .to_string()
                .contains("MISSING")
        );
        assert!(
            TOP.source("nope.wgsl")
                .unwrap_err()
                .to_string()
                .contains("top/nope.wgsl")
        );
        assert!(
            BASE.raw("top/k.wgsl")
                .unwrap_err()
                .to_string()
                .contains("not imported")
        );
    }
}
