#!/bin/sh
# runtime-libs.sh DEST BASE_PACKAGES BINARY...
#
# Copies into DEST (keeping their paths) the shared libraries the BINARYs
# load, found with ldd, plus the OpenNI2 drivers (libOpenNI2 dlopens them)
# and what those load, skipping the libraries of packages listed in
# BASE_PACKAGES (one name a line: what the runtime's base image already
# has). Writes DEST/usr/local/share/cornerpose/runtime-packages.txt: the
# Debian package and version each copied library came from.
#
# Why not `apt-get install` the runtime packages: PCL's I/O library depends
# on all of VTK, whose package dependencies bring LLVM, Mesa, MPI, ICU, PROJ
# and HDF5 (about 600 MB) that these binaries never load. Copying the ldd
# closure ships only what is loaded. A library that belongs to no package
# stops the build.
set -eu
dest=$1
base=$2
shift 2

drivers=$(ls /usr/lib/*-linux-gnu/OpenNI2/Drivers/*.so* 2>/dev/null || true)
list=$(mktemp)
for f in "$@" $drivers; do
  ldd "$f" | awk '$2 == "=>" && $3 ~ /^\// {print $3}'
done | sort -u >"$list"
for d in $drivers; do echo "$d" >>"$list"; done

packages=""
while read -r lib; do
  real=$(readlink -f "$lib")
  # The library's name in its canonical directory (/lib is /usr/lib here).
  link="$(readlink -f "$(dirname "$lib")")/$(basename "$lib")"
  pkg=$(dpkg -S "$real" 2>/dev/null || dpkg -S "$link" 2>/dev/null || dpkg -S "$lib" 2>/dev/null || true)
  pkg=$(echo "$pkg" | head -1 | cut -d: -f1)
  if [ -z "$pkg" ]; then
    echo "runtime-libs: $lib belongs to no package" >&2
    exit 1
  fi
  if grep -qx "$pkg" "$base"; then continue; fi
  mkdir -p "$dest$(dirname "$real")" "$dest$(dirname "$link")"
  cp -a "$real" "$dest$real"
  [ "$link" = "$real" ] || cp -a "$link" "$dest$link"
  packages="$packages $pkg"
done <"$list"
rm -f "$list"

# libOpenNI2's configuration (log settings, driver repository).
for f in /etc/openni2/OpenNI.ini; do
  if [ -f "$f" ]; then mkdir -p "$dest$(dirname "$f")" && cp -a "$f" "$dest$f"; fi
done

mkdir -p "$dest/usr/local/share/cornerpose"
# shellcheck disable=SC2086
dpkg-query -W -f='${Package} ${Version}\n' $(echo $packages | tr ' ' '\n' | sort -u) \
  >"$dest/usr/local/share/cornerpose/runtime-packages.txt"
echo "runtime-libs: $(find "$dest" -type f | wc -l) files from $(wc -l <"$dest/usr/local/share/cornerpose/runtime-packages.txt") packages:"
cat "$dest/usr/local/share/cornerpose/runtime-packages.txt"
