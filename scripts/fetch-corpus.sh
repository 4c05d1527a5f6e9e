#!/usr/bin/env bash
# Fills data/corpus/ with the test meshes shipped in Debian's libcgal-demo package (CGAL 5.5's
# data/meshes: OFF, PLY and STL models such as bunny00.off and mech-holes-shark.off).
# The .deb holds usr/share/doc/libcgal-dev/data.tar.gz, which holds data/meshes/.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
dest="$root/data/corpus"
if [ -f "$dest/bunny00.off" ] && [ -f "$dest/mech-holes-shark.off" ]; then
  exit 0  # already there: stay quiet
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
# apt-get download writes into the current directory; as root it warns about the _apt sandbox.
if ! apt-get download libcgal-demo >download.log 2>&1; then
  cat download.log >&2
  echo "fetch-corpus: could not download libcgal-demo (run 'apt-get update' first?)" >&2
  exit 1
fi
deb=$(ls libcgal-demo_*.deb)
ar x "$deb"
tar -xf data.tar.* ./usr/share/doc/libcgal-dev/data.tar.gz
tar -xzf usr/share/doc/libcgal-dev/data.tar.gz data/meshes
mkdir -p "$dest"
cp data/meshes/*.off data/meshes/*.ply data/meshes/*.stl "$dest/"
echo "$deb" >"$dest/SOURCE"
echo "fetch-corpus: $(ls "$dest" | grep -c -E '\.(off|ply|stl)$') meshes from $deb in data/corpus/"
