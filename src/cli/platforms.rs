//! The platforms of an FMU's binaries (FMI 2.0, section 2.2.1: the shared
//! library `binaries/<platform>/<modelIdentifier>.<so|dll|dylib>`): which
//! one this host is, which platform a library file is for, where cargo
//! leaves this crate's library for each platform, and how a missing one
//! is built.
//!
//! The win64 binary cross-built on Linux is for `x86_64-win7-windows-gnu`:
//! its std needs no Windows 10 API (`ProcessPrng`), so the one DLL runs on
//! Windows 7 and newer and under wine 8, where CI tests it. That target has
//! no prebuilt std: cargo builds std from the Rust source (`-Zbuild-std`),
//! which needs the source (rustup's `rust-src` or Debian's `rust-web-src`)
//! and `RUSTC_BOOTSTRAP=1` on a stable toolchain.

use super::CliError;
use crate::fmi::MODEL_IDENTIFIER;
use std::path::{Path, PathBuf};
use std::process::Command;

/// An FMI 2.0 platform this crate's binary is packed for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, clap::ValueEnum)]
pub enum Platform {
    /// 64-bit Linux: an ELF `.so`.
    Linux64,
    /// 64-bit Windows: a PE32+ `.dll`.
    Win64,
    /// 64-bit macOS: a Mach-O `.dylib`.
    Darwin64,
}

/// The cargo target of the win64 binary cross-built on Linux.
pub const WIN64_TARGET: &str = "x86_64-win7-windows-gnu";

/// The C compiler that links [`WIN64_TARGET`] (Debian: gcc-mingw-w64-x86-64).
pub const WIN64_LINKER: &str = "x86_64-w64-mingw32-gcc";

/// What to install for the win64 cross build, in its error messages.
const WIN64_INSTALL: &str = "on Debian `apt-get install rustc-web cargo-web rust-web-src \
     gcc-mingw-w64-x86-64`, elsewhere `rustup component add rust-src` and the MinGW-w64 gcc \
     (README, \"A Windows FMU\")";

impl Platform {
    /// Every platform, in the order the FMU lists them.
    pub const ALL: [Platform; 3] = [Platform::Linux64, Platform::Win64, Platform::Darwin64];

    /// The folder name under `binaries/`.
    pub fn name(self) -> &'static str {
        match self {
            Platform::Linux64 => "linux64",
            Platform::Win64 => "win64",
            Platform::Darwin64 => "darwin64",
        }
    }

    /// The extension of a shared library on this platform.
    pub fn extension(self) -> &'static str {
        match self {
            Platform::Linux64 => "so",
            Platform::Win64 => "dll",
            Platform::Darwin64 => "dylib",
        }
    }

    /// The binary's path inside the FMU.
    pub fn fmu_path(self) -> String {
        format!(
            "binaries/{}/{MODEL_IDENTIFIER}.{}",
            self.name(),
            self.extension()
        )
    }

    /// The file name cargo gives this crate's cdylib on this platform.
    pub fn cargo_file(self) -> String {
        match self {
            Platform::Win64 => format!("{MODEL_IDENTIFIER}.dll"),
            p => format!("lib{MODEL_IDENTIFIER}.{}", p.extension()),
        }
    }

    /// The platform of the machine this code runs on, if FMI 2.0 names one.
    pub fn host() -> Option<Platform> {
        if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
            Some(Platform::Linux64)
        } else if cfg!(all(windows, target_pointer_width = "64")) {
            Some(Platform::Win64)
        } else if cfg!(all(target_os = "macos", target_pointer_width = "64")) {
            Some(Platform::Darwin64)
        } else {
            None
        }
    }

    /// The platform of a shared library, read from its first bytes: a
    /// 64-bit ELF, PE32+ or Mach-O (thin or universal) file.
    pub fn of_binary(bytes: &[u8]) -> Option<Platform> {
        let u32_le = |at: usize| {
            let b = bytes.get(at..at + 4)?;
            Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        if bytes.starts_with(b"\x7fELF") && bytes.get(4) == Some(&2) {
            return Some(Platform::Linux64);
        }
        if bytes.starts_with(b"MZ") {
            // e_lfanew points at "PE\0\0"; the optional header's magic
            // (after the 20-byte COFF header) is 0x20b for PE32+.
            let pe = u32_le(0x3c)? as usize;
            let is_pe = bytes.get(pe..pe + 4)? == b"PE\0\0";
            let magic = bytes.get(pe + 24..pe + 26)?;
            return (is_pe && magic == [0x0b, 0x02]).then_some(Platform::Win64);
        }
        let magic = bytes.get(..4)?;
        // A universal binary: 0xcafebabe then a small count of architectures
        // (a Java class file has the same magic then its version, >= 45).
        let universal = magic == [0xca, 0xfe, 0xba, 0xbe]
            && bytes
                .get(4..8)
                .is_some_and(|n| n[..3] == [0, 0, 0] && n[3] < 20);
        (magic == [0xcf, 0xfa, 0xed, 0xfe] || universal).then_some(Platform::Darwin64)
    }
}

impl std::fmt::Display for Platform {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Where this executable's cargo build left things: its own folder
/// (`target/release/`) and the target folder above it.
#[derive(Clone, Debug)]
pub struct BuildTree {
    /// The executable's folder.
    pub exe_dir: PathBuf,
    /// The source tree the executable was built from, if it is still there.
    pub manifest: Option<PathBuf>,
}

impl BuildTree {
    /// The tree of the running executable.
    pub fn of_executable() -> Result<BuildTree, CliError> {
        let exe = std::env::current_exe().map_err(CliError::Executable)?;
        let exe_dir = exe
            .parent()
            .ok_or(CliError::NoExecutableFolder)?
            .to_path_buf();
        let manifest = Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml");
        Ok(BuildTree {
            exe_dir,
            manifest: manifest.is_file().then_some(manifest),
        })
    }

    /// The cargo target folder: the parent of `target/<profile>/` where the
    /// executable is; for an installed one (`cargo install --path .` puts
    /// it in ~/.cargo/bin), the source tree's `target/`.
    fn target_dir(&self) -> PathBuf {
        let in_target = self
            .exe_dir
            .file_name()
            .is_some_and(|n| n == "release" || n == "debug");
        match (&self.exe_dir.parent(), &self.manifest) {
            (Some(parent), _) if in_target => parent.to_path_buf(),
            (_, Some(manifest)) => manifest.with_file_name("target"),
            _ => self.exe_dir.clone(),
        }
    }

    /// The files where cargo leaves this crate's library for `platform`:
    /// next to the executable (or in its `deps/`, where `cargo test` leaves
    /// it; or in `target/release/` for an installed executable) for the
    /// host's platform; for win64 cross-built on another host,
    /// `target/x86_64-win7-windows-gnu/release/` (or the standard
    /// `x86_64-pc-windows-gnu`, Windows 10 and newer). darwin64 and linux64
    /// are only found on their own hosts: nothing here tests a cross-built
    /// one.
    pub fn candidates(&self, platform: Platform) -> Vec<PathBuf> {
        let file = platform.cargo_file();
        if Some(platform) == Platform::host() {
            return vec![
                self.target_dir().join("release").join(&file),
                self.exe_dir.join("deps").join(&file),
                self.exe_dir.join(&file),
            ];
        }
        match platform {
            Platform::Win64 => [WIN64_TARGET, "x86_64-pc-windows-gnu"]
                .iter()
                .map(|t| self.target_dir().join(t).join("release").join(&file))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The newest existing file of [`BuildTree::candidates`] (the last listed on a tie).
    pub fn find(&self, platform: Platform) -> Option<PathBuf> {
        let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
        self.candidates(platform)
            .into_iter()
            .filter_map(|p| modified(&p).map(|t| (t, p)))
            .max_by_key(|(t, _)| *t)
            .map(|(_, p)| p)
    }

    /// The cargo command that builds `platform`'s library in this tree, or
    /// why there is none (naming what to install).
    pub fn build_command(&self, platform: Platform) -> Result<Command, String> {
        let Some(manifest) = &self.manifest else {
            return Err(format!(
                "the source tree this executable was built from ({}) is gone, so it cannot be \
                 built here",
                env!("CARGO_MANIFEST_DIR")
            ));
        };
        let cargo = |program: &Path| {
            let mut c = Command::new(program);
            c.args(["build", "--release", "--lib", "--locked", "--manifest-path"])
                .arg(manifest)
                .arg("--target-dir")
                .arg(self.target_dir())
                .env_remove("CARGO_TARGET_DIR");
            c
        };
        if Some(platform) == Platform::host() {
            return Ok(cargo(Path::new("cargo")));
        }
        if platform != Platform::Win64 || Platform::host() != Some(Platform::Linux64) {
            return Err(unbuildable(platform));
        }
        let toolchain = match (on_path(WIN64_LINKER), rust_source_toolchain()) {
            (Some(_), Some(toolchain)) => toolchain,
            (linker, toolchain) => {
                let missing = match (linker, toolchain) {
                    (None, None) => format!("the Rust library source and {WIN64_LINKER}"),
                    (None, Some(_)) => WIN64_LINKER.to_string(),
                    _ => "the Rust library source (for -Zbuild-std)".to_string(),
                };
                return Err(format!(
                    "no {}, and {missing} to build one is not installed: {WIN64_INSTALL}",
                    win64_hint(self)
                ));
            }
        };
        let (cargo_path, rustc) = toolchain;
        // The linker by name and std with `test`, as scripts/windows_test.sh
        // gives them to `cargo test`: with another linker path or set of std
        // crates cargo rebuilds everything, std included.
        let mut c = cargo(&cargo_path);
        c.args([
            "--target",
            WIN64_TARGET,
            "-Zbuild-std=std,panic_unwind,test",
        ])
        .env("RUSTC", rustc)
        .env("RUSTC_BOOTSTRAP", "1")
        .env(
            format!(
                "CARGO_TARGET_{}_LINKER",
                WIN64_TARGET.to_uppercase().replace('-', "_")
            ),
            WIN64_LINKER,
        );
        Ok(c)
    }
}

/// What a missing binary of `platform` needs when this host cannot build it.
pub fn unbuildable(platform: Platform) -> String {
    let host = Platform::host().map_or("this host".to_string(), |h| format!("a {h} host"));
    match platform {
        Platform::Darwin64 => format!(
            "a darwin64 binary is built on a Mac (README, \"On macOS\"), not on {host}: nothing \
             here could test a cross-built one; pack one built there with --library \
             lib{MODEL_IDENTIFIER}.dylib"
        ),
        p => format!(
            "{host} does not build {p} binaries; build the FMU on {p}, or pack a {p} binary \
             built there with --library"
        ),
    }
}

/// Where the win64 binary was looked for, in messages.
fn win64_hint(tree: &BuildTree) -> String {
    let list: Vec<String> = tree
        .candidates(Platform::Win64)
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    format!("win64 binary at {}", list.join(" or "))
}

/// The file `program` in a folder of PATH.
fn on_path(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// A cargo and rustc pair whose sysroot holds the Rust library source,
/// for `-Zbuild-std`: the ones on PATH (rustup with `rust-src`), else
/// Debian's /usr/bin pair (`rust-web-src`).
fn rust_source_toolchain() -> Option<(PathBuf, PathBuf)> {
    let pairs = [
        (on_path("cargo"), on_path("rustc")),
        (
            Some(PathBuf::from("/usr/bin/cargo")),
            Some(PathBuf::from("/usr/bin/rustc")),
        ),
    ];
    pairs.into_iter().find_map(|pair| {
        let (Some(cargo), Some(rustc)) = pair else {
            return None;
        };
        let out = Command::new(&rustc)
            .args(["--print", "sysroot"])
            .env_remove("RUSTC_BOOTSTRAP")
            .output()
            .ok()?;
        let sysroot = String::from_utf8(out.stdout).ok()?;
        let std = Path::new(sysroot.trim()).join("lib/rustlib/src/rust/library/std/Cargo.toml");
        (out.status.success() && std.is_file() && cargo.is_file()).then_some((cargo, rustc))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_fmi_2() {
        let paths: Vec<String> = Platform::ALL.iter().map(|p| p.fmu_path()).collect();
        assert_eq!(
            paths,
            [
                "binaries/linux64/origami_fmu.so",
                "binaries/win64/origami_fmu.dll",
                "binaries/darwin64/origami_fmu.dylib"
            ]
        );
        assert_eq!(Platform::Win64.cargo_file(), "origami_fmu.dll");
        assert_eq!(Platform::Darwin64.cargo_file(), "liborigami_fmu.dylib");
    }

    /// The host is detected from how this code was compiled.
    #[test]
    fn host_platform() {
        #[cfg(all(target_os = "linux", target_arch = "x86_64"))]
        assert_eq!(Platform::host(), Some(Platform::Linux64));
        #[cfg(all(windows, target_arch = "x86_64"))]
        assert_eq!(Platform::host(), Some(Platform::Win64));
        #[cfg(all(target_os = "macos", target_pointer_width = "64"))]
        assert_eq!(Platform::host(), Some(Platform::Darwin64));
    }

    #[test]
    fn binary_formats() {
        let mut elf = b"\x7fELF\x02\x01\x01\0".to_vec();
        assert_eq!(Platform::of_binary(&elf), Some(Platform::Linux64));
        elf[4] = 1; // 32-bit
        assert_eq!(Platform::of_binary(&elf), None);
        let mut pe = vec![0u8; 0x100];
        pe[..2].copy_from_slice(b"MZ");
        pe[0x3c] = 0x80;
        pe[0x80..0x84].copy_from_slice(b"PE\0\0");
        pe[0x80 + 24..0x80 + 26].copy_from_slice(&[0x0b, 0x02]);
        assert_eq!(Platform::of_binary(&pe), Some(Platform::Win64));
        pe[0x80 + 24] = 0x0b;
        pe[0x80 + 25] = 0x01; // PE32: 32-bit
        assert_eq!(Platform::of_binary(&pe), None);
        pe[0x3c] = 0xff; // e_lfanew past the end
        assert_eq!(Platform::of_binary(&pe), None);
        let macho = [0xcf, 0xfa, 0xed, 0xfe, 7, 0, 0, 1];
        assert_eq!(Platform::of_binary(&macho), Some(Platform::Darwin64));
        let universal = [0xca, 0xfe, 0xba, 0xbe, 0, 0, 0, 2];
        assert_eq!(Platform::of_binary(&universal), Some(Platform::Darwin64));
        let java = [0xca, 0xfe, 0xba, 0xbe, 0, 0, 0, 61];
        assert_eq!(Platform::of_binary(&java), None);
        assert_eq!(Platform::of_binary(b"{\"scene\": 1}"), None);
        assert_eq!(Platform::of_binary(b""), None);
    }

    /// The library this test binary belongs to is of the host's platform.
    #[test]
    fn this_executable_is_of_the_host_platform() {
        let exe = std::fs::read(std::env::current_exe().unwrap()).unwrap();
        assert_eq!(Platform::of_binary(&exe), Platform::host());
    }

    /// An installed executable (~/.cargo/bin) finds the libraries in its
    /// source tree's target/.
    #[test]
    fn an_installed_executable_looks_in_its_source_tree() {
        let tree = BuildTree {
            exe_dir: PathBuf::from("/home/u/.cargo/bin"),
            manifest: Some(PathBuf::from("/src/origami-fmu/Cargo.toml")),
        };
        assert_eq!(tree.target_dir(), Path::new("/src/origami-fmu/target"));
        if let Some(host) = Platform::host() {
            let first = tree.candidates(host)[0].clone();
            assert_eq!(
                first,
                Path::new("/src/origami-fmu/target/release").join(host.cargo_file())
            );
        }
        let built = BuildTree {
            exe_dir: PathBuf::from("/w/target/release"),
            manifest: None,
        };
        assert_eq!(built.target_dir(), Path::new("/w/target"));
    }

    /// darwin64 is never found cross-built, and a host that cannot build a
    /// platform says where to build it.
    #[test]
    fn what_a_host_cannot_build() {
        let tree = BuildTree {
            exe_dir: PathBuf::from("/x/target/release"),
            manifest: None,
        };
        if Platform::host() != Some(Platform::Darwin64) {
            assert!(tree.candidates(Platform::Darwin64).is_empty());
            let e = unbuildable(Platform::Darwin64);
            assert!(e.contains("on a Mac") && e.contains("--library"), "{e}");
        }
        if Platform::host() == Some(Platform::Linux64) {
            assert_eq!(
                tree.candidates(Platform::Win64),
                [
                    PathBuf::from("/x/target/x86_64-win7-windows-gnu/release/origami_fmu.dll"),
                    PathBuf::from("/x/target/x86_64-pc-windows-gnu/release/origami_fmu.dll")
                ]
            );
            let e = tree.build_command(Platform::Win64).unwrap_err();
            assert!(e.contains("source tree"), "{e}");
        }
    }
}
