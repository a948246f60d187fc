//! `fathom list`: the registry, printed from the declarations.

use clap::Args;

#[derive(Args)]
pub struct ListArgs {}

pub fn run(_a: ListArgs) -> Result<(), String> {
    Err("list is not written yet".into())
}
