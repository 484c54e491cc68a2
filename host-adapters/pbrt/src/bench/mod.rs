//! `firemedium bench …`: the measurements behind docs/RESULTS.md, as commands anyone can rerun.

pub mod stability;

use clap::{Args, Subcommand};

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, Subcommand)]
enum What {
    /// Stiff and extreme cases, expected vs measured; exits 1 if any fails.
    Stability,
}

pub fn run(a: &BenchArgs) -> Result<String, (u8, String)> {
    match &a.what {
        What::Stability => {
            let start = std::time::Instant::now();
            let cases = stability::cases();
            let (table, ok) = stability::table(&cases);
            let failed = cases.iter().filter(|c| !c.pass).count();
            let summary = format!(
                "{} cases, {} failed, {:.2} s\n",
                cases.len(),
                failed,
                start.elapsed().as_secs_f64()
            );
            if ok {
                Ok(table + &summary)
            } else {
                print!("{table}");
                Err((
                    1,
                    format!("stability: {failed} of {} cases failed", cases.len()),
                ))
            }
        }
    }
}
