//! Where a method runs, chosen once for the workspace: the CLI's `--backend`, the
//! window's, and every renderer that has a CPU and a GPU side
//! ([`crate::cloudscape::CloudRenderer`] among them) take this one setting.

use crate::{Gpu, GpuError};

/// Where to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Backend {
    /// A hardware GPU when there is one, else the CPU (a software adapter such as
    /// llvmpipe is slower than atmo's own CPU path; [`Backend::Gpu`] still uses it).
    #[default]
    Auto,
    /// The GPU (wgpu), any adapter, software ones too; an error when there is none.
    Gpu,
    /// The CPU (rayon over every core).
    Cpu,
}

/// The device a [`Backend`] opened, and one line saying which and why.
pub struct Opened {
    /// The GPU to run on, or `None` for the CPU.
    pub gpu: Option<Gpu>,
    /// Which device runs, for the user's terminal.
    pub notice: String,
}

impl Backend {
    /// The names `auto`, `gpu` and `cpu`, as [`std::str::FromStr`] reads them.
    pub const NAMES: [&'static str; 3] = ["auto", "gpu", "cpu"];

    /// Whether a method runs on `gpu`, the device a window already has: always with
    /// [`Backend::Gpu`], never with [`Backend::Cpu`], with [`Backend::Auto`] where it is
    /// a hardware adapter.
    pub fn runs_on(self, gpu: &Gpu) -> bool {
        match self {
            Backend::Cpu => false,
            Backend::Gpu => true,
            Backend::Auto => !gpu.is_software(),
        }
    }

    /// Opens the device this backend asks for: the adapter `adapter` names (part of its
    /// name or a backend, see [`Gpu::new`]), or the best there is. [`Backend::Auto`]
    /// without `adapter` falls back to the CPU where there is no adapter or only a
    /// software one.
    pub fn open(self, adapter: Option<&str>) -> Result<Opened, GpuError> {
        if self == Backend::Cpu {
            return Ok(Opened {
                gpu: None,
                notice: "atmo: running on the CPU".into(),
            });
        }
        let fallback = self == Backend::Auto && adapter.is_none();
        match Gpu::new(adapter) {
            Ok(gpu) if fallback && gpu.is_software() => Ok(Opened {
                notice: format!(
                    "atmo: only a software GPU adapter ({}) found; running on the CPU, which \
                     is faster (--backend gpu to use it)",
                    gpu.describe()
                ),
                gpu: None,
            }),
            Ok(gpu) => Ok(Opened {
                notice: format!("atmo: running on the GPU: {}", gpu.describe()),
                gpu: Some(gpu),
            }),
            Err(GpuError::NoAdapter { .. }) if fallback => Ok(Opened {
                gpu: None,
                notice: "atmo: no GPU adapter found; running on the CPU".into(),
            }),
            Err(e) => Err(e),
        }
    }
}

impl std::str::FromStr for Backend {
    type Err = atmo::Error;

    fn from_str(text: &str) -> Result<Backend, atmo::Error> {
        match text {
            "auto" => Ok(Backend::Auto),
            "gpu" => Ok(Backend::Gpu),
            "cpu" => Ok(Backend::Cpu),
            _ => Err(atmo::Error::out_of_range(
                "backend",
                text,
                &Backend::NAMES.join(", "),
            )),
        }
    }
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Backend::Auto => "auto",
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_to_their_backends() {
        for name in Backend::NAMES {
            assert_eq!(name.parse::<Backend>().unwrap().to_string(), name);
        }
        let e = "metal".parse::<Backend>().unwrap_err().to_string();
        assert!(e.contains("backend") && e.contains("auto, gpu, cpu"), "{e}");
    }

    #[test]
    fn the_cpu_opens_no_device() {
        let opened = Backend::Cpu.open(Some("no such adapter")).unwrap();
        assert!(opened.gpu.is_none());
    }
}
