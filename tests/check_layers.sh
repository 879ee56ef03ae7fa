#!/usr/bin/env bash
# check_layers.sh [ROOT] — fails (status 1, one line per violation) when a project #include crosses
# a layer the wrong way. Scans every .c/.h under ROOT (default: the checkout) by path prefix, so
# subfolders (server/net/, core/<area>/sub/, ...) belong to their top folder's layer.
#
# Allowed matrix (a file under FROM may #include "X" only when X starts with one of TO):
#   FROM               TO
#   core/common/       core/common/                        (the error type: depends on nothing)
#   core/              core/                               (math only: no proto, client, server)
#   proto/wire_core_map.h  proto/ core/                    (header-only: the one mapping of each
#                                                           wire enum to core's; see below)
#   proto/             proto/ core/common/ core/mesh/      (the wire format carries meshes: df_mesh,
#                      core/admm/admm_defaults.h            mesh_io; never a solver; the ADMM
#                                                           defaults header is macros only)
#   client/deformctl/  client/ proto/ core/                (the CLI; core/kelvinlet for its local
#                                                           brush check)
#   client/            client/ proto/ core/common/ core/mesh/   (libdeformclient: no solver, no
#                                                           server; never client/deformctl/)
# proto/wire_core_map.h includes solver headers, so only server/ and client/deformctl/ (and
# tests) may include it: never the rest of proto/ nor libdeformclient (client/ outside deformctl).
#   server/hid/hid_pen_target.*  server/ core/common/ core/mesh/ core/geom/   (the pen's ray cast:
#                                                           session topology + Embree scene)
#   server/hid/hid_manager.*, server/hid/hid_mgr_*  server/ proto/ core/common/  (the daemon
#                                                           integration: devices -> requests)
#   server/hid/        server/ core/common/                (HID parsers: pure C, no proto, no math)
#   server/            server/ proto/ core/                (the daemon)
#   tests/             anything                            (tests may reach every layer)
# System headers (#include <...>) are not checked. A file under a folder not listed fails (a new
# top folder must be added to the matrix). Quoted includes must be repository paths ("core/...").
set -u
ROOT=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$ROOT" || exit 2

allowed() { # $1 = file, $2 = included path -> status 0 when allowed
  local f=$1 inc=$2
  case "$f" in
    tests/*) return 0 ;;
    core/common/*) [[ $inc == core/common/* ]] ;;
    core/*) [[ $inc == core/* ]] ;;
    proto/wire_core_map.h) [[ $inc == proto/* || $inc == core/* ]] ;;
    proto/*) [[ ( $inc == proto/* && $inc != proto/wire_core_map.h ) || $inc == core/common/* \
                || $inc == core/mesh/* || $inc == core/admm/admm_defaults.h ]] ;;
    client/deformctl/*) [[ $inc == client/* || $inc == proto/* || $inc == core/* ]] ;;
    client/*) [[ ( $inc == client/* && $inc != client/deformctl/* ) \
                 || ( $inc == proto/* && $inc != proto/wire_core_map.h ) \
                 || $inc == core/common/* || $inc == core/mesh/* ]] ;;
    server/hid/hid_pen_target.*) [[ $inc == server/* || $inc == core/common/* \
                                     || $inc == core/mesh/* || $inc == core/geom/* ]] ;;
    server/hid/hid_manager.*|server/hid/hid_mgr_*) [[ $inc == server/* || $inc == proto/* \
                                                    || $inc == core/common/* ]] ;;
    server/hid/*) [[ $inc == server/* || $inc == core/common/* ]] ;;
    server/*) [[ $inc == server/* || $inc == proto/* || $inc == core/* ]] ;;
    *) return 1 ;;
  esac
}

bad=0; files=0
while IFS= read -r f; do
  f=${f#./}
  files=$((files + 1))
  while IFS=: read -r line inc; do
    if ! allowed "$f" "$inc"; then
      echo "layer violation: $f:$line includes \"$inc\""
      bad=$((bad + 1))
    fi
  done < <(grep -n -E '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$f" \
             | sed -E 's/^([0-9]+):[^"]*"([^"]+)".*/\1:\2/')
done < <(find . \( -path ./build -o -path './build-*' -o -path ./.git -o -path '*/python' \) -prune \
           -o \( -name '*.c' -o -name '*.h' \) -type f -print | sort)

if [ "$bad" -gt 0 ]; then
  echo "check_layers: $bad include(s) cross a layer (matrix: tests/check_layers.sh)"
  exit 1
fi
echo "check_layers: $files files, every #include within its layer"
