//! Typed GPU buffers: Pod arrays for storage, encase structs for uniforms,
//! and `Result`-returning readback.

use std::marker::PhantomData;
use std::ops::Range;

use bytemuck::Pod;
use encase::{ShaderType, UniformBuffer as EncaseUniform, internal::WriteInto};
use wgpu::util::DeviceExt;

use super::Gpu;
use crate::error::{Error, Result};

/// A storage buffer of `len` elements of Pod type `T`.
#[derive(Debug)]
pub struct GpuArray<T: Pod> {
    pub buffer: wgpu::Buffer,
    len: usize,
    label: String,
    _t: PhantomData<T>,
}

const STORAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

impl<T: Pod> GpuArray<T> {
    fn check_size(gpu: &Gpu, label: &str, len: usize) -> Result<u64> {
        let bytes = (len.max(1) as u64).saturating_mul(std::mem::size_of::<T>() as u64);
        if bytes > gpu.max_binding_bytes() {
            return Err(Error::limit(
                format!(
                    "bytes of `{label}` (one storage binding; split the data with `chunk_ranges`)"
                ),
                bytes,
                gpu.max_binding_bytes(),
            ));
        }
        Ok(bytes)
    }

    /// Uploads `data` into a new storage buffer (readable and writable by kernels).
    pub fn from_slice(gpu: &Gpu, label: &str, data: &[T]) -> Result<Self> {
        Self::check_size(gpu, label, data.len())?;
        let label = format!("chisel.{label}");
        let zero = [T::zeroed()];
        let contents: &[T] = if data.is_empty() { &zero } else { data };
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&label),
                contents: bytemuck::cast_slice(contents),
                usage: STORAGE,
            });
        Ok(GpuArray {
            buffer,
            len: data.len(),
            label,
            _t: PhantomData,
        })
    }

    /// A new buffer of `len` copies of `sentinel` (e.g. NaN or `u32::MAX`),
    /// so a kernel that misses an element is caught by the comparison.
    pub fn filled(gpu: &Gpu, label: &str, len: usize, sentinel: T) -> Result<Self> {
        Self::check_size(gpu, label, len)?;
        Self::from_slice(gpu, label, &vec![sentinel; len])
    }

    /// A kernel's output: filled with `sentinel` when the device was opened
    /// with [`super::GpuOptions::sentinels`] (tests, `CHISEL_GPU_SENTINELS=1`),
    /// else cleared on the device, so production pays no host upload.
    pub fn output(gpu: &Gpu, label: &str, len: usize, sentinel: T) -> Result<Self> {
        if gpu.sentinels() {
            Self::filled(gpu, label, len, sentinel)
        } else {
            Self::zeroed(gpu, label, len)
        }
    }

    /// A new buffer of `len` zeros, cleared on the device (nothing crosses
    /// the bus): for outputs a kernel writes in full before anything reads
    /// them, where a sentinel would never be checked.
    pub fn zeroed(gpu: &Gpu, label: &str, len: usize) -> Result<Self> {
        let bytes = Self::check_size(gpu, label, len)?;
        let label = format!("chisel.{label}");
        let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&label),
            size: bytes.max(std::mem::size_of::<T>() as u64),
            usage: STORAGE,
            mapped_at_creation: false,
        });
        Ok(GpuArray {
            buffer,
            len,
            label,
            _t: PhantomData,
        })
    }

    /// Wraps an existing buffer holding `len` elements.
    pub(crate) fn from_raw(buffer: wgpu::Buffer, len: usize, label: &str) -> Self {
        GpuArray {
            buffer,
            len,
            label: format!("chisel.{label}"),
            _t: PhantomData,
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the array has no elements.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes of the elements (0 for an empty array).
    pub fn byte_len(&self) -> u64 {
        (self.len * std::mem::size_of::<T>()) as u64
    }

    /// The whole buffer as a binding resource.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }

    /// The wgpu label, `chisel.<kernel>.<buffer>`.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// Overwrites the elements from `data` (same length).
    pub fn write(&self, gpu: &Gpu, data: &[T]) -> Result<()> {
        if data.len() != self.len {
            return Err(Error::mismatch(
                format!("elements written to `{}`", self.label),
                self.len,
                data.len(),
            ));
        }
        if !data.is_empty() {
            gpu.queue
                .write_buffer(&self.buffer, 0, bytemuck::cast_slice(data));
        }
        Ok(())
    }

    /// Copies the elements back to the host; waits for queued work first.
    pub fn read(&self, gpu: &Gpu) -> Result<Vec<T>> {
        let mut encoder = gpu.encoder("readback");
        let staging = self.stage(gpu, &mut encoder)?;
        gpu.submit_and_wait(encoder)?;
        staging.finish(gpu)
    }

    /// Records a copy into a mappable staging buffer on `encoder`; call
    /// [`Staged::finish`] after submitting to get the data.
    pub fn stage(&self, gpu: &Gpu, encoder: &mut wgpu::CommandEncoder) -> Result<Staged<T>> {
        let staged = self.staging(gpu);
        staged.copy_from(encoder, self);
        Ok(staged)
    }

    /// A mappable staging buffer of this array's size, for read-backs
    /// repeated many times ([`Staged::copy_from`], then [`Staged::finish`]).
    pub fn staging(&self, gpu: &Gpu) -> Staged<T> {
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{}.staging", self.label)),
            size: self.byte_len().max(4),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Staged {
            staging,
            len: self.len,
            label: self.label.clone(),
            _t: PhantomData,
        }
    }
}

/// A staging buffer a copy is recorded into, then mapped; see
/// [`GpuArray::stage`] (once) and [`GpuArray::staging`] (reused).
#[derive(Debug)]
pub struct Staged<T: Pod> {
    staging: wgpu::Buffer,
    len: usize,
    label: String,
    _t: PhantomData<T>,
}

impl<T: Pod> Staged<T> {
    /// Records a copy of `src` (of this staging buffer's length) on `encoder`.
    pub fn copy_from(&self, encoder: &mut wgpu::CommandEncoder, src: &GpuArray<T>) {
        let bytes = (self.len.min(src.len) * std::mem::size_of::<T>()) as u64;
        if bytes > 0 {
            encoder.copy_buffer_to_buffer(&src.buffer, 0, &self.staging, 0, bytes);
        }
    }

    /// Maps the staging buffer and copies it out (after the copy was
    /// submitted); unmapped again, so it can take the next copy.
    pub fn finish(&self, gpu: &Gpu) -> Result<Vec<T>> {
        if self.len == 0 {
            return Ok(Vec::new());
        }
        let bytes = (self.len * std::mem::size_of::<T>()) as u64;
        let (tx, rx) = std::sync::mpsc::channel();
        self.staging
            .map_async(wgpu::MapMode::Read, 0..bytes, move |r| {
                let _ = tx.send(r);
            });
        gpu.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map_err(|e| Error::Readback {
                label: self.label.clone(),
                message: e.to_string(),
            })?;
        gpu.check_errors()?;
        let mapped = rx.recv().map_err(|_| Error::Readback {
            label: self.label.clone(),
            message: "map callback never ran".into(),
        })?;
        mapped.map_err(|e| Error::Readback {
            label: self.label.clone(),
            message: e.to_string(),
        })?;
        let out = {
            let view = self
                .staging
                .get_mapped_range(0..bytes)
                .map_err(|e| Error::Readback {
                    label: self.label.clone(),
                    message: e.to_string(),
                })?;
            bytemuck::pod_collect_to_vec(&view)
        };
        self.staging.unmap();
        Ok(out)
    }
}

/// A uniform buffer holding one encase [`ShaderType`] value (std140 layout).
#[derive(Debug)]
pub struct UniformBuffer<T> {
    pub buffer: wgpu::Buffer,
    label: String,
    _t: PhantomData<T>,
}

impl<T: ShaderType + WriteInto> UniformBuffer<T> {
    /// Uploads `value` laid out by encase.
    pub fn new(gpu: &Gpu, label: &str, value: &T) -> Result<Self> {
        let mut bytes = EncaseUniform::new(Vec::<u8>::new());
        bytes.write(value).map_err(|e| Error::Validation {
            label: label.into(),
            message: e.to_string(),
        })?;
        let label = format!("chisel.{label}");
        let buffer = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&label),
                contents: &bytes.into_inner(),
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            });
        Ok(UniformBuffer {
            buffer,
            label,
            _t: PhantomData,
        })
    }

    /// The buffer as a binding resource.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.buffer.as_entire_binding()
    }

    /// The wgpu label, `chisel.<kernel>.params`.
    pub fn label(&self) -> &str {
        &self.label
    }
}

/// Splits `n` elements of `elem_bytes` each into consecutive ranges of at
/// most `max_bytes` per range (at least one element each). This is how data
/// larger than one storage binding is processed in slabs.
pub fn chunk_ranges(n: usize, elem_bytes: usize, max_bytes: u64) -> Vec<Range<usize>> {
    let per = usize::try_from(max_bytes / elem_bytes.max(1) as u64)
        .unwrap_or(usize::MAX)
        .max(1);
    (0..n.div_ceil(per))
        .map(|i| i * per..((i + 1) * per).min(n))
        .collect()
}

/// Splits the rows of CSR arrays into consecutive row ranges whose entries
/// fit one storage binding each: `arrays` lists each CSR's offsets (one
/// more than the rows, shared row numbering) with its bytes per entry. A
/// row too large for a binding on its own gets a range of its own (its
/// upload then reports the limit).
pub fn row_chunks(arrays: &[(&[u32], u64)], max_bytes: u64) -> Vec<Range<usize>> {
    let n_rows = arrays.first().map_or(0, |(o, _)| o.len().saturating_sub(1));
    let bytes = |r: Range<usize>| -> u64 {
        (arrays.iter())
            .map(|(o, b)| u64::from(o[r.end] - o[r.start]) * b)
            .max()
            .unwrap_or(0)
    };
    let mut out = Vec::new();
    let mut start = 0;
    while start < n_rows {
        let mut end = start + 1;
        // Doubling then bisection keeps this O(chunks · log rows).
        let mut step = 1;
        while end + step <= n_rows && bytes(start..end + step) <= max_bytes {
            end += step;
            step *= 2;
        }
        while step > 1 {
            step /= 2;
            if end + step <= n_rows && bytes(start..end + step) <= max_bytes {
                end += step;
            }
        }
        out.push(start..end);
        start = end;
    }
    out
}
