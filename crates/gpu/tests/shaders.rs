//! Every WGSL file under `shaders/` parses and validates with naga; needs no GPU.

#[test]
fn every_shader_parses_and_validates() {
    let names: Vec<_> = gpu::shader::names().collect();
    assert!(!names.is_empty(), "no shaders found under shaders/");
    let mut failures = Vec::new();
    for name in names {
        let src = gpu::shader::source(name).expect("embedded shader resolves");
        match naga::front::wgsl::parse_str(&src) {
            Err(e) => failures.push(format!("{name}: parse: {}", e.emit_to_string(&src))),
            Ok(module) => {
                let mut v = naga::valid::Validator::new(
                    naga::valid::ValidationFlags::all(),
                    naga::valid::Capabilities::all(),
                );
                if let Err(e) = v.validate(&module) {
                    failures.push(format!("{name}: validate: {}", e.emit_to_string(&src)));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "invalid shaders:\n{}",
        failures.join("\n")
    );
}

#[test]
fn unknown_shader_is_an_error() {
    let err = gpu::shader::source("nope/missing.wgsl").unwrap_err();
    assert!(err.to_string().contains("nope/missing.wgsl"));
}
