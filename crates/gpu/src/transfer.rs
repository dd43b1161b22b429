//! Upload and readback helpers. Readback is for tests, examples and the final image of a
//! program: nothing reads back between the passes of a pipeline.

use wgpu::util::DeviceExt;

use crate::GpuError;

/// Fails with [`GpuError::TooLarge`] when `size` bytes exceed the device's buffer limits for `usage`.
pub fn check_buffer_size(
    device: &wgpu::Device,
    what: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> Result<(), GpuError> {
    let limits = device.limits();
    let mut limit = limits.max_buffer_size;
    if usage.contains(wgpu::BufferUsages::STORAGE) {
        limit = limit.min(limits.max_storage_buffer_binding_size);
    }
    if usage.contains(wgpu::BufferUsages::UNIFORM) {
        limit = limit.min(limits.max_uniform_buffer_binding_size);
    }
    if size > limit {
        return Err(GpuError::TooLarge {
            what: what.into(),
            needed: size,
            limit,
        });
    }
    Ok(())
}

/// Fails with [`GpuError::TooLarge`] when a 2D texture of `width × height` exceeds the device limit.
pub fn check_texture_size(
    device: &wgpu::Device,
    what: &str,
    width: u32,
    height: u32,
) -> Result<(), GpuError> {
    let limit = device.limits().max_texture_dimension_2d;
    let needed = width.max(height);
    if needed > limit || width == 0 || height == 0 {
        return Err(GpuError::TooLarge {
            what: format!("{what} ({width}×{height})"),
            needed: u64::from(needed),
            limit: u64::from(limit),
        });
    }
    Ok(())
}

/// Runs `allocate` (which creates buffers and textures) inside an out-of-memory error scope:
/// an allocation the device cannot satisfy is [`GpuError::OutOfMemory`] naming `what`,
/// instead of wgpu's uncaptured-error panic.
pub fn allocation<T, E: From<GpuError>>(
    device: &wgpu::Device,
    what: &str,
    allocate: impl FnOnce() -> Result<T, E>,
) -> Result<T, E> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let result = allocate();
    match pollster::block_on(scope.pop()) {
        Some(e) => Err(GpuError::OutOfMemory {
            what: what.into(),
            message: e.to_string(),
        }
        .into()),
        None => result,
    }
}

/// Usage of a compute kernel's output texture: written as storage, then sampled or copied out.
pub const STORAGE_OUTPUT: wgpu::TextureUsages = wgpu::TextureUsages::STORAGE_BINDING
    .union(wgpu::TextureUsages::TEXTURE_BINDING)
    .union(wgpu::TextureUsages::COPY_SRC);

/// [`STORAGE_OUTPUT`] that can also be uploaded into: a texture any kernel of a chain may read
/// or write, and tests fill and read back.
pub const STORAGE_ANY: wgpu::TextureUsages = STORAGE_OUTPUT.union(wgpu::TextureUsages::COPY_DST);

/// A 2D texture with one mip level and one sample.
pub fn texture_2d(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A 2D texture (size-checked) filled with `texels`: tightly packed rows of
/// `width × block size` bytes. `COPY_DST` is added to `usage`.
#[allow(clippy::too_many_arguments)]
pub fn texture_init(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
    texels: &[u8],
) -> Result<wgpu::Texture, GpuError> {
    check_texture_size(device, label, width, height)?;
    let texel = format.block_copy_size(None).unwrap_or(4);
    let expected = u64::from(width) * u64::from(height) * u64::from(texel);
    if texels.len() as u64 != expected {
        return Err(GpuError::DataSize(format!(
            "{label}: {} bytes of texels given, {width}×{height} {format:?} needs {expected}",
            texels.len()
        )));
    }
    let texture = texture_2d(
        device,
        label,
        width,
        height,
        format,
        usage | wgpu::TextureUsages::COPY_DST,
    );
    write_level0(queue, &texture, texels);
    Ok(texture)
}

/// Writes tightly packed `texels` into mip level 0 of a 2D `texture` (with `COPY_DST`) whose
/// level 0 they fill exactly (the caller checks the size).
pub fn write_level0(queue: &wgpu::Queue, texture: &wgpu::Texture, texels: &[u8]) {
    let texel = texture.format().block_copy_size(None).unwrap_or(4);
    let size = wgpu::Extent3d {
        depth_or_array_layers: 1,
        ..texture.size()
    };
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        texels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(size.width * texel),
            rows_per_image: Some(size.height),
        },
        size,
    );
}

/// Three-component vectors padded to four with `w`, the 16-byte stride WGSL storage arrays of
/// `vec3<f32>` / `vec4<f32>` need.
pub fn vec4s<T: Copy + Into<[f32; 3]>>(v: &[T], w: f32) -> Vec<[f32; 4]> {
    v.iter()
        .map(|&p| {
            let [x, y, z] = p.into();
            [x, y, z, w]
        })
        .collect()
}

/// An uninitialised (zeroed) buffer of `size` bytes (at least 16, so empty inputs still bind),
/// size-checked.
pub fn buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    check_buffer_size(device, label, size, usage)?;
    Ok(device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage,
        mapped_at_creation: false,
    }))
}

/// A buffer holding `contents` (at least 4 bytes, so empty inputs still bind), size-checked.
pub fn buffer_init(
    device: &wgpu::Device,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    check_buffer_size(device, label, contents.len() as u64, usage)?;
    let padded;
    let contents = if contents.len() < 4 {
        padded = [0u8; 4];
        &padded[..]
    } else {
        contents
    };
    Ok(
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        }),
    )
}

fn map_and_copy(device: &wgpu::Device, staging: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let bytes = slice
        .get_mapped_range()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .to_vec();
    staging.unmap();
    Ok(bytes)
}

/// Copies a whole buffer (which needs `COPY_SRC`) back to the CPU.
pub fn read_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<u8>, GpuError> {
    let encoder = device.create_command_encoder(&Default::default());
    read_after(device, queue, encoder, buffer, 0..buffer.size())
}

/// Submits `encoder` with a copy of `range` of `buffer` (which needs `COPY_SRC`; offset and
/// length multiples of 4) appended, and returns those bytes: work recorded on the GPU and
/// its result read back in one round trip.
pub fn read_after(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut encoder: wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
    range: std::ops::Range<u64>,
) -> Result<Vec<u8>, GpuError> {
    let size = range.end.saturating_sub(range.start);
    check_buffer_size(device, "readback", size, wgpu::BufferUsages::MAP_READ)?;
    if size == 0 {
        queue.submit([encoder.finish()]);
        return Ok(Vec::new());
    }
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_buffer_to_buffer(buffer, range.start, &staging, 0, size);
    queue.submit([encoder.finish()]);
    map_and_copy(device, &staging)
}

/// [`read_buffer`] as values of `T` (copied, so any alignment of the bytes is fine; a
/// trailing partial value is dropped).
pub fn read_pod<T: bytemuck::Pod>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<T>, GpuError> {
    let bytes = read_buffer(device, queue, buffer)?;
    let size = size_of::<T>().max(1);
    let whole = bytes.len() / size * size;
    Ok(bytemuck::pod_collect_to_vec(&bytes[..whole]))
}

/// Copies mip 0 of a 2D texture (which needs `COPY_SRC`) back to the CPU with tightly packed
/// rows, every array layer after the one before. For depth-stencil formats, `aspect` picks
/// the plane (e.g. `DepthOnly`).
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, GpuError> {
    read_texture_level(device, queue, texture, aspect, 0)
}

/// [`read_texture`] of mip level `level`.
pub fn read_texture_level(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    aspect: wgpu::TextureAspect,
    level: u32,
) -> Result<Vec<u8>, GpuError> {
    let texel = u64::from(
        texture
            .format()
            .block_copy_size(Some(aspect))
            .ok_or_else(|| {
                GpuError::Readback(format!(
                    "format {:?} has no copyable aspect {aspect:?}",
                    texture.format()
                ))
            })?,
    );
    let size = texture.size().mip_level_size(level, texture.dimension());
    let (w, h) = (u64::from(size.width), u64::from(size.height));
    // Rows of every layer: layers are images of `h` rows, one after the other.
    let rows = h * u64::from(texture.depth_or_array_layers());
    let row = w * texel;
    let align = u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let padded_row = row.div_ceil(align) * align;
    check_buffer_size(
        device,
        "texture readback",
        padded_row * rows,
        wgpu::BufferUsages::MAP_READ,
    )?;
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: padded_row * rows,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: level,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row as u32),
                rows_per_image: Some(h as u32),
            },
        },
        wgpu::Extent3d {
            depth_or_array_layers: texture.depth_or_array_layers(),
            ..size
        },
    );
    queue.submit([encoder.finish()]);
    let padded = map_and_copy(device, &staging)?;
    let mut out = Vec::with_capacity((row * rows) as usize);
    for y in 0..rows as usize {
        let start = y * padded_row as usize;
        out.extend_from_slice(&padded[start..start + row as usize]);
    }
    Ok(out)
}
