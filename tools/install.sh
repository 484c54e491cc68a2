#!/usr/bin/env bash
# Installs firemedium under a prefix: the command (and firemedium-bench, which `firemedium bench` runs) in PREFIX/bin, the plugin it loads in PREFIX/lib/firemedium (where
# the command looks for it, relative to itself), the C header in PREFIX/include. Builds the release first unless
# --no-build (then it installs what target/release holds). Then `firemedium` works from any directory once
# PREFIX/bin is on the PATH.
#
#   bash tools/install.sh                 # ~/.local
#   bash tools/install.sh /opt/firemedium
#   bash tools/install.sh --no-build /tmp/fm
set -euo pipefail
cd "$(dirname "$0")/.."
build=1
if [[ "${1:-}" == "--no-build" ]]; then
    build=0
    shift
fi
prefix="${1:-$HOME/.local}"
case "$(uname -s)" in
    Darwin) lib="libfiremedium_plugin.dylib" ;;
    MINGW* | MSYS* | CYGWIN*) lib="firemedium_plugin.dll" ;;
    *) lib="libfiremedium_plugin.so" ;;
esac
exe="firemedium"
[[ -f target/release/firemedium.exe ]] && exe="firemedium.exe"
if [[ $build == 1 ]]; then
    cargo build --release -p firemedium -p firemedium-plugin -p firemedium-bench
fi
# (After `cargo test` alone the plugin is only in target/release/deps.)
libpath="target/release/$lib"
[[ -f "$libpath" ]] || libpath="target/release/deps/$lib"
for f in "target/release/$exe" "$libpath"; do
    if [[ ! -f "$f" ]]; then
        echo "install: $f is missing (build with: cargo build --release)" >&2
        exit 1
    fi
done
mkdir -p "$prefix/bin" "$prefix/lib/firemedium" "$prefix/include"
# Through a temporary name and a rename: a running firemedium keeps its file, a new one replaces it whole.
install_file() {
    cp "$1" "$2.tmp.$$"
    chmod "$3" "$2.tmp.$$"
    mv -f "$2.tmp.$$" "$2"
}
install_file "target/release/$exe" "$prefix/bin/$exe" 755
bench="firemedium-bench${exe#firemedium}"
if [[ -f "target/release/$bench" ]]; then
    install_file "target/release/$bench" "$prefix/bin/$bench" 755
fi
install_file "$libpath" "$prefix/lib/firemedium/$lib" 755
install_file plugin/abi/include/firemedium.h "$prefix/include/firemedium.h" 644
echo "installed $prefix/bin/$exe, $prefix/lib/firemedium/$lib and $prefix/include/firemedium.h"
case ":$PATH:" in
    *":$prefix/bin:"*) ;;
    *) echo "add $prefix/bin to your PATH (e.g. export PATH=\"$prefix/bin:\$PATH\")" ;;
esac
