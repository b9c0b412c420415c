#!/usr/bin/env bash
# Fails unless LIBRARY's DT_NEEDED entries are all Vulkan's loader or the C/C++ runtime: the library an engine
# loads must not drag in gust's tool dependencies (OpenVDB, Boost, TBB...).
# Usage: check_needed.sh LIBRARY
set -euo pipefail
needed="$(readelf --dynamic "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p')"
echo "$1 needs:" $needed
status=0
for lib in $needed; do
  case "$lib" in
    libvulkan.so.1 | libstdc++.so.6 | libm.so.6 | libgcc_s.so.1 | libc.so.6 | ld-linux-x86-64.so.2) ;;
    *) echo "needs $lib, beyond Vulkan's loader and the C/C++ runtime" >&2; status=1 ;;
  esac
done
exit $status
