// TEMPORARY (not committed): runs the viewer as `mislab view` will, until main.rs is wired.
use clap::Parser;
#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: mislab::viewer::ViewArgs,
}
fn main() {
    env_logger::init();
    let cli = Cli::parse();
    if let Err(e) = mislab::viewer::run(cli.args) {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}
