//! `cargo xtask`: builds the two firmware images (each in its own cargo invocation: their
//! embassy time drivers cannot share one build) and writes flashable files to `dist/`.
//!
//! ```text
//! cargo xtask build flight [--sparky2] [--bootloader]   # one image, release
//! cargo xtask build module [--uf2]
//! cargo xtask dist                                       # every variant → dist/*.{elf,bin,hex,uf2,tlfw}
//! cargo xtask size                                       # text/data/bss of what dist/ holds
//! cargo xtask verify                                     # each file against its boot contract
//! cargo xtask readme                                     # the README's sizes table from dist/
//! cargo xtask figures [--check | --write]                # the docs' M4 instruction figures
//! ```

use fw_elf as elf;
mod figures;
mod formats;
mod layout;
mod tlfw;
mod verify;

use layout::Layout;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::{env, fs};

use clap::{Parser, Subcommand};

/// Builds the TauLink firmware images (release, thumbv7em-none-eabihf) and turns them into
/// flashable .bin, .hex and .uf2 files.
#[derive(Parser, Debug)]
#[command(
    name = "xtask",
    version,
    after_help = "Examples:
  cargo xtask build flight --sparky2     the Sparky2 image, prints the ELF's path
  cargo xtask build module --uf2         the nRF52840 image for a UF2 bootloader
  cargo xtask dist                       every variant -> dist/*.{elf,bin,hex,uf2}
  cargo xtask size                       text/data/bss of what dist/ holds"
)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Subcommand, Debug)]
enum Task {
    /// Build one firmware image (release) and print the ELF's path.
    #[command(subcommand)]
    Build(Image),
    /// Build every variant and write dist/NAME.elf, .bin and .hex (and .uf2, .tlfw where the
    /// image has them).
    Dist,
    /// Print text/data/bss of the ELFs in dist/.
    Size,
    /// Check every file in dist/ against its bootloader's boot contract, and the README's
    /// sizes table against dist/ (fails when stale).
    Verify,
    /// Rewrite the README's sizes table from the ELFs in dist/.
    Readme,
    /// Build the m4-bench programs, count their instructions under QEMU (m4count) and print
    /// the named figures; with --check fail when a figure marked `<!-- m4:NAME -->` in a
    /// Markdown file differs, with --write rewrite them.
    Figures {
        /// Fail (exit 1) when a marked figure in the docs is stale.
        #[arg(long, conflicts_with = "write")]
        check: bool,
        /// Rewrite every marked figure in the docs.
        #[arg(long)]
        write: bool,
    },
}

#[derive(Subcommand, Debug)]
enum Image {
    /// The flight controller (STM32F405; BrushedSparky unless told otherwise).
    Flight {
        /// Build for the Sparky2 board instead of the BrushedSparky.
        #[arg(long)]
        sparky2: bool,
        /// Link at 0x08020000 behind the Tau Labs bootloader instead of at 0x08000000.
        #[arg(long)]
        bootloader: bool,
    },
    /// The TauLink module (nRF52840).
    Module {
        /// Link at 0x26000 behind a UF2 bootloader (nice!nano and friends) and write a .uf2.
        #[arg(long)]
        uf2: bool,
    },
}

const TARGET: &str = "thumbv7em-none-eabihf";

/// One firmware variant: which package, which features, what to call the files.
struct Variant {
    package: &'static str,
    features: &'static [&'static str],
    name: &'static str,
    /// Write a UF2 file (nRF52840 behind a UF2 bootloader).
    uf2: bool,
    /// Write a Tau Labs `.tlfw` for this board type and revision.
    tlfw: Option<(u8, u8)>,
    /// The boot contract the files must keep.
    layout: &'static Layout,
}

const VARIANTS: &[Variant] = &[
    Variant {
        package: "flight-fw",
        features: &[],
        name: "flight-brushedsparky",
        uf2: false,
        tlfw: None,
        layout: &layout::F405_DIRECT,
    },
    Variant {
        package: "flight-fw",
        features: &["sparky2"],
        name: "flight-sparky2",
        uf2: false,
        tlfw: None,
        layout: &layout::F405_DIRECT,
    },
    Variant {
        package: "flight-fw",
        features: &["taulabs-bootloader"],
        name: "flight-brushedsparky-taulabs-bl",
        uf2: false,
        tlfw: Some((tlfw::BOARD_TYPE_SPARKY2, tlfw::REVISION_BRUSHEDSPARKY)),
        layout: &layout::F405_TAULABS,
    },
    Variant {
        package: "flight-fw",
        features: &["sparky2", "taulabs-bootloader"],
        name: "flight-sparky2-taulabs-bl",
        uf2: false,
        tlfw: Some((tlfw::BOARD_TYPE_SPARKY2, tlfw::REVISION_SPARKY2)),
        layout: &layout::F405_TAULABS,
    },
    Variant {
        package: "module-fw",
        features: &[],
        name: "module-nrf52840",
        uf2: false,
        tlfw: None,
        layout: &layout::NRF_PROBE,
    },
    Variant {
        package: "module-fw",
        features: &["uf2"],
        name: "module-nrf52840-uf2",
        uf2: true,
        tlfw: None,
        layout: &layout::NRF_UF2,
    },
];

/// Version tag written into `.tlfw` descriptors.
const TLFW_TAG: &str = concat!("taulink-", env!("CARGO_PKG_VERSION"));

fn workspace_root() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    root.canonicalize().unwrap_or(root)
}

fn target_dir() -> PathBuf {
    env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("target"))
}

fn build(package: &str, features: &[&str]) -> Result<PathBuf, String> {
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(workspace_root()).args([
        "build",
        "--release",
        "--target",
        TARGET,
        "-p",
        package,
    ]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    let status = cmd.status().map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err(format!("building {package} failed"));
    }
    Ok(target_dir().join(TARGET).join("release").join(package))
}

/// Builds every m4-bench program (release, for the M4).
fn build_benches() -> Result<(), String> {
    let cargo = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(workspace_root())
        .args(["build", "--release", "--target", TARGET, "-p", "m4-bench"])
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !status.success() {
        return Err("building m4-bench failed".into());
    }
    Ok(())
}

fn write_outputs(variant: &Variant, elf_path: &Path, dist: &Path) -> Result<(), String> {
    let elf = fs::read(elf_path).map_err(|e| format!("{}: {e}", elf_path.display()))?;
    let segments = elf::load_segments(&elf).map_err(|e| format!("{}: {e}", elf_path.display()))?;
    let sizes = elf::sizes(&elf).map_err(|e| e.to_string())?;
    let (start, bin) = formats::to_bin(&segments);
    let write = |ext: &str, bytes: &[u8]| {
        let path = dist.join(format!("{}.{ext}", variant.name));
        fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("elf", &elf)?;
    write("bin", &bin)?;
    write("hex", formats::to_ihex(&segments).as_bytes())?;
    if variant.uf2 {
        write(
            "uf2",
            &formats::to_uf2(&segments, formats::UF2_FAMILY_NRF52840),
        )?;
    }
    if let Some((board_type, revision)) = variant.tlfw {
        write("tlfw", &tlfw::package(&bin, board_type, revision, TLFW_TAG))?;
    }
    println!(
        "{:<34} text {:>7}  data {:>5}  bss {:>6}  flash from 0x{start:08X}, .bin {} bytes",
        variant.name,
        sizes.text,
        sizes.data,
        sizes.bss,
        bin.len()
    );
    Ok(())
}

fn dist() -> Result<(), String> {
    let dist = workspace_root().join("dist");
    fs::create_dir_all(&dist).map_err(|e| format!("{}: {e}", dist.display()))?;
    let mut built = Vec::new();
    for v in VARIANTS {
        let elf = build(v.package, v.features)?;
        // The next variant of the same package overwrites the ELF: keep a copy first.
        let keep = dist.join(format!("{}.elf", v.name));
        fs::copy(&elf, &keep).map_err(|e| format!("{}: {e}", keep.display()))?;
        built.push((v, keep));
    }
    println!("\nflashable files in {}:", dist.display());
    for (v, elf) in built {
        write_outputs(v, &elf, &dist)?;
    }
    Ok(())
}

fn size() -> Result<(), String> {
    let dist = workspace_root().join("dist");
    for v in VARIANTS {
        let path = dist.join(format!("{}.elf", v.name));
        let Ok(elf) = fs::read(&path) else {
            println!("{:<34} (not built: run `cargo xtask dist`)", v.name);
            continue;
        };
        let s = elf::sizes(&elf).map_err(|e| format!("{}: {e}", path.display()))?;
        println!(
            "{:<34} text {:>7}  data {:>5}  bss {:>6}",
            v.name, s.text, s.data, s.bss
        );
    }
    Ok(())
}

/// Where the README's generated sizes table starts and ends.
const SIZES_BEGIN: &str = "<!-- xtask sizes: begin (cargo xtask readme writes this table) -->";
const SIZES_END: &str = "<!-- xtask sizes: end -->";

/// The sizes table for the README, from the ELFs in dist/.
fn sizes_table() -> Result<String, String> {
    let dist = workspace_root().join("dist");
    let mut t = String::from(
        "| image | flash from | flash used | text | data | bss |\n|---|---|---|---|---|---|\n",
    );
    for v in VARIANTS {
        let path = dist.join(format!("{}.elf", v.name));
        let elf = fs::read(&path)
            .map_err(|e| format!("{}: {e} (run `cargo xtask dist`)", path.display()))?;
        let s = elf::sizes(&elf).map_err(|e| format!("{}: {e}", path.display()))?;
        let segments = elf::load_segments(&elf).map_err(|e| format!("{}: {e}", path.display()))?;
        let used: usize = segments.iter().map(|s| s.data.len()).sum();
        t.push_str(&format!(
            "| `{}` | 0x{:08X} | {} B | {} B | {} B | {} B |\n",
            v.name, v.layout.origin, used, s.text, s.data, s.bss
        ));
    }
    Ok(t)
}

/// README.md with the sizes table replaced, or an error if the markers are missing.
fn readme_with_sizes(readme: &str, table: &str) -> Result<String, String> {
    let start = readme
        .find(SIZES_BEGIN)
        .ok_or("README.md has no sizes begin marker")?
        + SIZES_BEGIN.len();
    let end = readme
        .get(start..)
        .and_then(|rest| rest.find(SIZES_END))
        .ok_or("README.md has no sizes end marker")?
        + start;
    Ok(format!(
        "{}\n{table}{}",
        readme.get(..start).unwrap_or_default(),
        readme.get(end..).unwrap_or_default()
    ))
}

fn readme() -> Result<(), String> {
    let path = workspace_root().join("README.md");
    let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let new = readme_with_sizes(&text, &sizes_table()?)?;
    fs::write(&path, new).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("sizes table in {} updated", path.display());
    Ok(())
}

fn verify() -> Result<(), String> {
    let dist = workspace_root().join("dist");
    let read = |v: &Variant, ext: &str| fs::read(dist.join(format!("{}.{ext}", v.name))).ok();
    let mut failed = 0;
    for v in VARIANTS {
        let Some(elf) = read(v, "elf") else {
            println!(
                "FAIL {:<34} dist/{0}.elf missing: run `cargo xtask dist`",
                v.name
            );
            failed += 1;
            continue;
        };
        let (bin, uf2, tl) = (read(v, "bin"), read(v, "uf2"), read(v, "tlfw"));
        let mut problems = Vec::new();
        if v.tlfw.is_some() && tl.is_none() {
            problems.push("no .tlfw written".to_string());
        }
        let files = verify::Files {
            elf: &elf,
            bin: bin.as_deref(),
            uf2: uf2.as_deref(),
            tlfw: tl.as_deref().zip(v.tlfw).map(|(f, (t, r))| (f, t, r)),
        };
        problems.extend(verify::check(v.layout, &files));
        println!(
            "{} {:<34} behind {}",
            if problems.is_empty() { "ok  " } else { "FAIL" },
            v.name,
            v.layout.starter
        );
        for p in &problems {
            println!("       {p}");
        }
        failed += usize::from(!problems.is_empty());
    }
    // The README's sizes are generated; a stale table is a failure, not a footnote.
    let path = workspace_root().join("README.md");
    let text = fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    if readme_with_sizes(&text, &sizes_table()?)? != text {
        println!("FAIL README.md sizes table is stale: run `cargo xtask readme`");
        failed += 1;
    } else {
        println!("ok   README.md sizes table matches dist/");
    }
    if failed > 0 {
        return Err(format!("{failed} check(s) failed"));
    }
    Ok(())
}

fn run(task: &Task) -> Result<(), String> {
    match task {
        Task::Build(image) => {
            let (package, wanted) = match *image {
                Image::Flight {
                    sparky2,
                    bootloader,
                } => (
                    "flight-fw",
                    vec![(sparky2, "sparky2"), (bootloader, "taulabs-bootloader")],
                ),
                Image::Module { uf2 } => ("module-fw", vec![(uf2, "uf2")]),
            };
            let features: Vec<&str> = wanted
                .into_iter()
                .filter_map(|(on, f)| on.then_some(f))
                .collect();
            let elf = build(package, &features)?;
            println!("{}", elf.display());
            Ok(())
        }
        Task::Dist => dist(),
        Task::Size => size(),
        Task::Verify => verify(),
        Task::Readme => readme(),
        Task::Figures { check, write } => {
            let mode = match (check, write) {
                (true, _) => figures::Mode::Check,
                (_, true) => figures::Mode::Write,
                _ => figures::Mode::Print,
            };
            build_benches()?;
            let elf_dir = target_dir().join(TARGET).join("release");
            figures::run(&workspace_root(), &elf_dir, mode)
        }
    }
}

fn main() -> ExitCode {
    // clap prints --help/--version (exit 0) and usage errors with a suggestion (exit 2).
    let cli = Cli::parse();
    match run(&cli.task) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn readme_sizes_table_is_replaced_between_the_markers() {
        let text = format!("intro\n{SIZES_BEGIN}\nold table\n{SIZES_END}\noutro\n");
        let new = readme_with_sizes(&text, "| new |\n").unwrap();
        assert_eq!(
            new,
            format!("intro\n{SIZES_BEGIN}\n| new |\n{SIZES_END}\noutro\n")
        );
        assert_eq!(readme_with_sizes(&new, "| new |\n").unwrap(), new);
        assert!(readme_with_sizes("no markers", "x").is_err());
    }

    #[test]
    fn every_layout_has_a_sparky2_build() {
        let flight: Vec<_> = VARIANTS
            .iter()
            .filter(|v| v.package == "flight-fw")
            .collect();
        for layout in [&layout::F405_DIRECT, &layout::F405_TAULABS] {
            assert!(
                flight
                    .iter()
                    .any(|v| std::ptr::eq(v.layout, layout) && v.features.contains(&"sparky2")),
                "no Sparky2 build behind {}",
                layout.starter
            );
        }
    }
}
