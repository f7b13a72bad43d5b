//! The `flatray` binary: runs [`flatray_cli::run`] and exits with its code.

fn main() {
    flatray_cli::exit_cleanly_on_interrupt();
    let code = flatray_cli::run(
        std::env::args_os(),
        &mut std::io::stdout(),
        &mut std::io::stderr(),
    );
    std::process::exit(code);
}
