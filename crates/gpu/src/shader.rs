//! WGSL loading from the workspace's `shaders/` folder.
//!
//! WGSL has no include mechanism; a file may start with lines of the form
//! `// #import gbuffer/normal_encoding.wgsl`, and [`source`] prepends those files (recursively,
//! each once). Every file is embedded at build time, so programs run from any directory.

use crate::GpuError;

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// Names of all WGSL files, relative to `shaders/` (e.g. `gbuffer/gbuffer.wgsl`).
pub fn names() -> impl Iterator<Item = &'static str> {
    SHADERS.iter().map(|(name, _)| *name)
}

fn raw(name: &str) -> Result<&'static str, GpuError> {
    SHADERS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, src)| *src)
        .ok_or_else(|| GpuError::Shader {
            name: name.into(),
            message: "no such file under shaders/".into(),
        })
}

/// The source of a shader with its `#import`s resolved.
pub fn source(name: &str) -> Result<String, GpuError> {
    let mut seen = Vec::new();
    let mut out = String::new();
    resolve(name, &mut seen, &mut out)?;
    Ok(out)
}

fn resolve(name: &str, seen: &mut Vec<String>, out: &mut String) -> Result<(), GpuError> {
    if seen.iter().any(|s| s == name) {
        return Ok(());
    }
    seen.push(name.to_owned());
    let src = raw(name)?;
    for line in src.lines() {
        if let Some(dep) = line.trim().strip_prefix("// #import ") {
            resolve(dep.trim(), seen, out)?;
        }
    }
    out.push_str(&format!("// ---- {name}\n"));
    out.push_str(src);
    out.push('\n');
    Ok(())
}

/// Compiles a shader from `shaders/` into a module.
pub fn module(device: &wgpu::Device, name: &str) -> Result<wgpu::ShaderModule, GpuError> {
    Ok(module_from_source(device, name, source(name)?))
}

/// Compiles WGSL text (e.g. [`source`] after a rewrite) into a module labelled `label`.
pub fn module_from_source(device: &wgpu::Device, label: &str, src: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    })
}

/// A compute pipeline for `entry` of `module` with the layout derived from the shader and the
/// given values of its `override` constants.
pub fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: None,
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// A bind group for group 0 of `pipeline` (auto layout) with whole buffers at the given
/// bindings.
pub fn bind_buffers(
    device: &wgpu::Device,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    entries: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = entries
        .iter()
        .map(|&(binding, b)| wgpu::BindGroupEntry {
            binding,
            resource: b.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    })
}
