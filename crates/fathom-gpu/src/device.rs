//! Adapter and device set-up, headless or for a window's surface. A missing adapter, a refused
//! device and a lost device all become [`GpuError`]s with advice, never panics: wgpu's default
//! handler of uncaptured errors panics, so ours records the first error (and logs each to
//! stderr), and every wait returns it.

use crate::error::GpuError;
use std::sync::{Arc, Mutex};

/// A wgpu device with its queue and what we know about the adapter.
pub struct Gpu {
    /// The logical device every buffer and pipeline is made on.
    pub device: wgpu::Device,
    /// The queue work is submitted to.
    pub queue: wgpu::Queue,
    /// The adapter's description (name, backend, device type).
    pub info: wgpu::AdapterInfo,
    /// Limits of the device we were given.
    pub limits: wgpu::Limits,
    /// Set by the device-lost callback; checked after every wait.
    lost: Slot,
    /// The first error wgpu reported outside an error scope; checked after every wait.
    uncaptured: Slot,
}

type Slot = Arc<Mutex<Option<String>>>;

/// Records a lost device and the first uncaptured error instead of panicking.
fn install_handlers(device: &wgpu::Device) -> (Slot, Slot) {
    let lost = Arc::new(Mutex::new(None));
    let l = lost.clone();
    device.set_device_lost_callback(move |reason, msg| {
        if let Ok(mut g) = l.lock() {
            *g = Some(format!("{reason:?}: {msg}"));
        }
    });
    let uncaptured = Arc::new(Mutex::new(None));
    let u = uncaptured.clone();
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        eprintln!("fathom: GPU error: {e}");
        if let Ok(mut g) = u.lock() {
            g.get_or_insert_with(|| e.to_string());
        }
    }));
    (lost, uncaptured)
}

/// The backends to try: `WGPU_BACKEND` when set, otherwise wgpu's defaults (Vulkan, Metal,
/// DX12, GL as the platform has them).
pub fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env())
}

impl Gpu {
    /// A headless device (compute and offscreen rendering only).
    pub fn headless() -> Result<Gpu, GpuError> {
        Self::new(&instance(), None)
    }

    /// A headless device on Vulkan only (unless `WGPU_BACKEND` chooses otherwise): what the
    /// tests use, so that a machine without Vulkan fails loudly instead of silently falling
    /// back to a slow GL emulation.
    pub fn headless_vulkan() -> Result<Gpu, GpuError> {
        Self::headless_vulkan_limited(|_| {})
    }

    /// Like [`Gpu::headless_vulkan`], with the device's limits lowered by `shrink` from the
    /// adapter's: how the tests check that a device too small for a tape or an image gives
    /// clear errors.
    pub fn headless_vulkan_limited(
        shrink: impl FnOnce(&mut wgpu::Limits),
    ) -> Result<Gpu, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if std::env::var_os("WGPU_BACKEND").is_none() {
            desc.backends = wgpu::Backends::VULKAN;
        }
        let backends = desc.backends;
        Self::with_limits(&wgpu::Instance::new(desc), None, shrink).map_err(|e| match e {
            GpuError::NoAdapter { .. } => GpuError::NoAdapter {
                backends: format!("{backends:?}"),
            },
            e => e,
        })
    }

    /// A device that can present to `surface` (pass `None` for headless).
    pub fn new(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Gpu, GpuError> {
        Self::with_limits(instance, surface, |_| {})
    }

    /// A device with the adapter's limits as changed by `shrink` (which may only lower them).
    fn with_limits(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
        shrink: impl FnOnce(&mut wgpu::Limits),
    ) -> Result<Gpu, GpuError> {
        let backends = wgpu::InstanceDescriptor::new_without_display_handle_from_env().backends;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: surface,
            ..Default::default()
        }))
        .map_err(|_| GpuError::NoAdapter {
            backends: format!("{backends:?}"),
        })?;
        let info = adapter.get_info();
        // Ask for everything the adapter offers: the renderer needs 6 storage buffers in one
        // stage (more than the downlevel defaults) and reports the real buffer and texture
        // limits in its errors.
        let mut limits = adapter.limits();
        shrink(&mut limits);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("fathom"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::RequestDevice {
            adapter: info.name.clone(),
            message: e.to_string(),
        })?;
        let (lost, uncaptured) = install_handlers(&device);
        Ok(Gpu {
            device,
            queue,
            info,
            limits,
            lost,
            uncaptured,
        })
    }

    /// A `Gpu` on a device someone else created (a window's, so the renderer's images can be
    /// shown without leaving the device). Installs the same lost-device and error handlers.
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue, info: wgpu::AdapterInfo) -> Gpu {
        let limits = device.limits();
        let (lost, uncaptured) = install_handlers(&device);
        Gpu {
            device,
            queue,
            info,
            limits,
            lost,
            uncaptured,
        }
    }

    /// "name (backend, device type)", for reports and benchmarks.
    pub fn adapter_name(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }

    /// Whether the adapter is a CPU implementation (lavapipe, llvmpipe, WARP): its timings are
    /// CPU timings.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Waits for submitted work, with a timeout so a runaway shader cannot hang the caller.
    pub fn wait(&self, timeout_s: u64) -> Result<(), GpuError> {
        let r = self.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(std::time::Duration::from_secs(timeout_s)),
        });
        self.check_lost()?;
        match r {
            Ok(_) => Ok(()),
            Err(wgpu::PollError::Timeout) => Err(GpuError::Timeout(timeout_s)),
            Err(e) => Err(GpuError::DeviceLost(e.to_string())),
        }
    }

    /// Errors out when the device-lost callback has fired, or wgpu reported an error
    /// outside an error scope (a destroyed device, for one, reports only that way until the
    /// next poll fires the lost callback). A lost device stays lost; an uncaptured error is
    /// reported once, so one failed frame does not disable a long-lived renderer.
    pub fn check_lost(&self) -> Result<(), GpuError> {
        if let Some(m) = self.lost.lock().ok().and_then(|g| g.clone()) {
            return Err(GpuError::DeviceLost(m));
        }
        match self.uncaptured.lock().ok().and_then(|mut g| g.take()) {
            Some(m) => Err(GpuError::Driver {
                what: "a GPU command".into(),
                message: m,
            }),
            None => Ok(()),
        }
    }

    /// Marks the device lost (tests use it to check the error path without a real reset).
    pub fn simulate_loss(&self, why: &str) {
        if let Ok(mut g) = self.lost.lock() {
            *g = Some(why.to_string());
        }
    }

    /// Copies `size` bytes of `src` into a fresh mappable buffer and reads them back.
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fathom readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        enc.copy_buffer_to_buffer(src, 0, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.wait(120)?;
        match rx.recv_timeout(std::time::Duration::from_secs(5)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(GpuError::DeviceLost(format!("readback failed: {e}"))),
            Err(_) => return Err(GpuError::Timeout(125)),
        }
        let data = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| GpuError::DeviceLost(format!("readback failed: {e}")))?
            .to_vec();
        staging.unmap();
        Ok(data)
    }
}
