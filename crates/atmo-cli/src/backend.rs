//! `--backend` and `--adapter`: where a method runs, chosen once at the edge.

use anyhow::Result;
use atmo_gpu::{Gpu, GpuError};
use clap::{Args, ValueEnum};

/// Where to run.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// A hardware GPU when there is one, else the CPU (a software adapter such as
    /// llvmpipe is slower than atmo's own CPU path; `--backend gpu` still uses it).
    Auto,
    /// The GPU (wgpu); an error when there is none.
    Gpu,
    /// The CPU (rayon over both cores).
    Cpu,
}

#[derive(Args)]
pub struct BackendArgs {
    /// Where to run the method: auto (a hardware GPU when there is one, else the CPU),
    /// gpu (any adapter, software ones too) or cpu.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,
    /// The GPU adapter: part of its name (`llvmpipe`) or a backend (`vulkan`, `metal`,
    /// `dx12`); default: WGPU_ADAPTER_NAME, else the fastest there is.
    #[arg(long, value_name = "NAME")]
    pub adapter: Option<String>,
}

impl BackendArgs {
    /// The GPU to run on, or `None` for the CPU; prints which device runs, in one line.
    pub fn open(&self) -> Result<Option<Gpu>> {
        if self.backend == Backend::Cpu {
            return Ok(None);
        }
        match Gpu::new(self.adapter.as_deref()) {
            Ok(gpu)
                if gpu.is_software() && self.backend == Backend::Auto && self.adapter.is_none() =>
            {
                eprintln!(
                    "atmo: only a software GPU adapter ({}) found; running on the CPU, which \
                     is faster (--backend gpu to use it)",
                    gpu.describe()
                );
                Ok(None)
            }
            Ok(gpu) => {
                eprintln!("atmo: running on the GPU: {}", gpu.describe());
                Ok(Some(gpu))
            }
            Err(GpuError::NoAdapter { .. })
                if self.backend == Backend::Auto && self.adapter.is_none() =>
            {
                eprintln!("atmo: no GPU adapter found; running on the CPU");
                Ok(None)
            }
            Err(e) => Err(gpu_error(e)),
        }
    }
}

/// A GPU error as the CLI reports it, with the flag that is the way out: what the user
/// can act on (no adapter, a missing feature, a limit, bad input) exits with 2, like
/// any other bad input.
pub fn gpu_error(e: GpuError) -> anyhow::Error {
    // The library's own errors about the input stand as they are.
    let e = match e {
        GpuError::Atmo(e) => return e.into(),
        e => e,
    };
    let flag = match e {
        GpuError::NoMatch { .. } => "--adapter names one of those, or --backend cpu",
        _ => "--backend cpu renders on the CPU",
    };
    let message = format!("{e} ({flag})");
    match e {
        GpuError::NoAdapter { .. }
        | GpuError::NoMatch { .. }
        | GpuError::MissingFeature { .. }
        | GpuError::OverLimit { .. } => atmo::Error::Invalid(message).into(),
        _ => anyhow::anyhow!(message),
    }
}
