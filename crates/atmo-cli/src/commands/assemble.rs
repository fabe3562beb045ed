//! `atmo assemble`: the animated PNG of an animation drawn in chunks (`--frames A..B`),
//! once every chunk is done, from one folder or several.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct AssembleArgs {
    /// The folders the chunks drew into (one, or one per chunk): each with the same
    /// atmo-frames.json, together holding every frame.
    #[arg(required = true, value_name = "FOLDER")]
    folders: Vec<PathBuf>,
    /// The animated PNG to write (.png or .apng).
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
}

pub fn run(args: AssembleArgs) -> Result<()> {
    let start = Instant::now();
    let frames = crate::output::assemble(&args.folders, &args.output)?;
    note!(
        "atmo: {} ({frames} frames) in {:.1} s",
        args.output.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
