//! `fathom bench eval`: throughput of the tape interpreter.

use clap::Args;

#[derive(Args)]
pub struct EvalArgs {}

pub fn run(_a: EvalArgs) -> Result<(), String> {
    Err("bench eval is not written yet".into())
}
