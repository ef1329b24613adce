#!/usr/bin/env bash
# Pack a build's binary with every shared library it loads, glibc and its loader included, into a
# tarball that runs on another x86-64 Linux machine without installing anything: used to run
# scripts/operator_search.py on the device machines' many cores (docs/teleop.md, "Operator search on many cores").
#   scripts/bundle_bench.sh [BINARY] [OUT.txz]   (defaults: build/bin/pmg_teleop_bench, .bundle/bench.txz)
# There:  tar xJf bench.txz && PMG_DATA_DIR=<a checkout> bundle/run.sh --task box ...
set -euo pipefail
bin=${1:-build/bin/pmg_teleop_bench}
out=${2:-.bundle/bench.txz}
[[ -x "$bin" ]] || { echo "bundle_bench.sh: $bin: no such executable (build first: scripts/build.sh)" >&2; exit 1; }
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/bundle/lib"
cp "$bin" "$stage/bundle/"
ldd "$bin" | awk '$3 ~ /^\// {print $3} $1 ~ /^\// {print $1}' | sort -u | while read -r lib; do
  cp -L "$lib" "$stage/bundle/lib/"
done
loader=$(ls "$stage"/bundle/lib/ld-linux-x86-64.so.* | head -1)
name=$(basename "$bin")
cat > "$stage/bundle/run.sh" <<RUN
#!/bin/sh
# $name with its own libraries and loader; data from \$PMG_DATA_DIR (default: the working directory)
here=\$(cd "\$(dirname "\$0")" && pwd)
export PMG_DATA_DIR="\${PMG_DATA_DIR:-\$PWD}"
exec "\$here/lib/$(basename "$loader")" --library-path "\$here/lib" "\$here/$name" "\$@"
RUN
chmod +x "$stage/bundle/run.sh"
strip --strip-unneeded "$stage/bundle/$name" 2>/dev/null || true
mkdir -p "$(dirname "$out")"
tar -C "$stage" -cJf "$out" bundle
echo "$out: $(du -h "$out" | cut -f1), $(ls "$stage/bundle/lib" | wc -l) libraries"
