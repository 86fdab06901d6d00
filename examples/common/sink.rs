//! Command-line helpers shared by the examples. Where the examples send their Rerun logs:
//! `--rrd PATH` (a folder for several runs, else a file), `--connect [ADDR]` (a running viewer,
//! default address if none), `--no-log`. Default: save under `out/<example>/`.

#![allow(dead_code)]

use std::path::PathBuf;

/// The chosen sink.
#[derive(Clone, Debug)]
pub enum Sink {
    /// Save `.rrd` files in this folder.
    Folder(PathBuf),
    /// Stream to a viewer.
    Connect(Option<String>),
    /// Log nothing.
    Off,
}

/// Reads the sink from the arguments.
pub fn from_args(example: &str) -> Sink {
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--no-log") {
        return Sink::Off;
    }
    if let Some(i) = args.iter().position(|a| a == "--connect") {
        let addr = args.get(i + 1).filter(|a| !a.starts_with("--")).cloned();
        return Sink::Connect(addr);
    }
    if let Some(path) = args
        .iter()
        .position(|a| a == "--rrd")
        .and_then(|i| args.get(i + 1))
    {
        return Sink::Folder(PathBuf::from(path));
    }
    Sink::Folder(PathBuf::from("out").join(example))
}

/// Prints how to look at what was saved.
pub fn print_how_to_view(sink: &Sink, files: &[PathBuf]) {
    match sink {
        Sink::Folder(dir) if !files.is_empty() => {
            println!(
                "\nwrote {} Rerun recording(s) to {}/; view them with:",
                files.len(),
                dir.display()
            );
            println!(
                "  rerun {}",
                files
                    .iter()
                    .map(|f| f.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" ")
            );
            println!("(the viewer: pip install rerun-sdk==0.36.3)");
        }
        Sink::Connect(addr) => println!(
            "\nstreamed to the viewer at {}",
            addr.as_deref().unwrap_or("the default address")
        ),
        _ => {}
    }
}

/// Prints that logging is compiled out, and exactly how to get a recording.
pub fn print_no_feature(example: &str, first_file: &str) {
    println!(
        "\nNo Rerun recording: this build has no `rerun` feature. To record the runs and view one:"
    );
    println!("  cargo run --release --features rerun --example {example}");
    println!("  pip install rerun-sdk==0.36.3");
    println!("  rerun out/{example}/{first_file}");
    println!("(the first build with `rerun` compiles its SDK; README, \"Viewing runs in Rerun\", says how long)");
}

/// The value after `name` on the command line, parsed, or `default`.
pub fn arg<T: std::str::FromStr>(name: &str, default: T) -> T {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Whether the command line has the flag `name`.
pub fn flag(name: &str) -> bool {
    std::env::args().any(|a| a == name)
}

/// A 3D recorder for `sink`: application `app`, saved as `file` in a folder sink; `None` (and a
/// message) when the sink is off or the recorder cannot start.
#[cfg(feature = "rerun")]
pub fn recorder_3d(
    sink: &Sink,
    app: &'static str,
    file: &str,
    options: sinew::dim3::RecorderOptions,
) -> Option<sinew::dim3::RerunRecorder> {
    use sinew::dim3::RerunRecorder;
    let made = match sink {
        Sink::Folder(dir) => RerunRecorder::save(app, dir.join(file), options).map(Some),
        Sink::Connect(addr) => RerunRecorder::connect(app, addr.as_deref(), options).map(Some),
        Sink::Off => Ok(None),
    };
    made.unwrap_or_else(|e| {
        eprintln!("not logging: {e}");
        None
    })
}
