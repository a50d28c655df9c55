//! Links the `mrsim` binary with the code of an agent's wake-up side by
//! side (link/wake.ld): fewer pages and cache lines touched per tick by
//! every agent process. Only on Linux with the GNU toolchain (the linker
//! is rust-lld or GNU ld, both of which read the script's `INSERT`); not
//! when the build picks another linker (mold, gold) through its flags, nor
//! with `MRSIM_NO_WAKE_LAYOUT=1` in the build's environment (to compare).

use std::env;
use std::path::Path;

fn main() {
    println!("cargo:rerun-if-changed=link/wake.ld");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=MRSIM_NO_WAKE_LAYOUT");
    let os = env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let abi = env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
    let flags = env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    let other_linker = ["mold", "gold"].iter().any(|l| flags.contains(l));
    let declined = env::var_os("MRSIM_NO_WAKE_LAYOUT").is_some_and(|v| v != "0");
    if os != "linux" || abi != "gnu" || other_linker || declined {
        return;
    }
    let Ok(dir) = env::var("CARGO_MANIFEST_DIR") else {
        return;
    };
    let script = Path::new(&dir).join("link").join("wake.ld");
    let script = script.to_string_lossy();
    // Tells the tests the layout was asked for (tests/it/bench.rs checks it).
    println!("cargo:rustc-env=MRSIM_WAKE_LAYOUT=1");
    // `-Wl,` splits at commas: a path with one goes as the driver's `-T`.
    if script.contains(',') {
        println!("cargo:rustc-link-arg-bin=mrsim=-T{script}");
    } else {
        println!("cargo:rustc-link-arg-bin=mrsim=-Wl,-T,{script}");
    }
}
