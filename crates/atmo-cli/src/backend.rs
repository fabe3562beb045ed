//! `--backend` and `--adapter`: where a method runs, chosen once at the edge.

use anyhow::Result;
pub use atmo_gpu::Backend;
use atmo_gpu::{Gpu, GpuError};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;

/// `--backend`'s parser: the names of [`Backend`], offered as clap's possible values.
pub fn backend_parser() -> impl TypedValueParser<Value = Backend> {
    PossibleValuesParser::new(Backend::NAMES).map(|name| name.parse().expect("one of NAMES"))
}

#[derive(Args)]
pub struct BackendArgs {
    /// Where to run the method: auto (a hardware GPU when there is one, else the CPU),
    /// gpu (any adapter, software ones too) or cpu.
    #[arg(long, value_parser = backend_parser(), default_value_t = Backend::Auto)]
    pub backend: Backend,
    /// The GPU adapter: part of its name (`llvmpipe`) or a backend (`vulkan`, `metal`,
    /// `dx12`); default: WGPU_ADAPTER_NAME, else the fastest there is.
    #[arg(long, value_name = "NAME")]
    pub adapter: Option<String>,
}

impl BackendArgs {
    /// The GPU to run on, or `None` for the CPU; prints which device runs, in one line
    /// (not for the CPU asked for by name).
    pub fn open(&self) -> Result<Option<Gpu>> {
        let opened = self
            .backend
            .open(self.adapter.as_deref())
            .map_err(gpu_error)?;
        if self.backend != Backend::Cpu {
            note!("{}", opened.notice);
        }
        Ok(opened.gpu)
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
