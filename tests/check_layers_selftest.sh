#!/usr/bin/env bash
# check_layers_selftest.sh — tests tests/check_layers.sh on throw-away trees: a tree that keeps to
# the matrix passes, and each fake violation (one per rule, subfolders included) fails with a line
# naming the file. Exit status 0 when every case behaves.
set -u
CHECK="$(cd "$(dirname "$0")" && pwd)/check_layers.sh"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fails=0

put() { mkdir -p "$(dirname "$1")"; printf '%s\n' "${@:2}" > "$1"; }
clean_tree() { # $1 = dir: one legitimate include per layer
  rm -rf "$1"; mkdir -p "$1"
  put "$1/core/common/df_error.h" '#include <stdio.h>'
  put "$1/core/mesh/mesh.h" '#include "core/common/df_error.h"'
  put "$1/core/kelvinlet/k.c" '#include "core/kelvinlet/k.h"' '#include "core/common/df_error.h"'
  put "$1/proto/messages.h" '#include "core/mesh/mesh.h"' '#include "proto/frame.h"'
  put "$1/client/dc.c" '#include "proto/messages.h"' '#include "client/dc.h"'
  put "$1/client/deformctl/cmd.c" '#include "core/kelvinlet/k.h"' '#include "client/dc.h"' \
    '#include "proto/wire_core_map.h"'
  put "$1/proto/wire_core_map.h" '#include "core/kelvinlet/k.h"' '#include "proto/messages.h"'
  put "$1/proto/msg_h.c" '#include "core/admm/admm_defaults.h"'
  put "$1/server/net/conn.c" '#include "server/exec/pool.h"' '#include "core/admm/admm.h"'
  put "$1/tests/unit/x/test_x.c" '#include "server/net/conn.h"'
  put "$1/server/hid/hid_pen_target.c" '#include "core/geom/raycast.h"' '#include "core/mesh/mesh.h"'
  put "$1/server/hid/hid_manager.c" '#include "proto/messages.h"' '#include "server/exec/job.h"'
  put "$1/server/hid/hid_mgr_drive.c" '#include "proto/messages.h"' '#include "core/common/df_error.h"'
}

case_ok() { # $1 = name
  clean_tree "$tmp/t"
  if ! out=$(bash "$CHECK" "$tmp/t"); then echo "FAIL $1: clean tree rejected: $out"; fails=$((fails + 1))
  else echo "ok   $1"; fi
}
case_bad() { # $1 = file, $2 = include: must be reported
  clean_tree "$tmp/t"
  put "$tmp/t/$1" "#include <stdlib.h>" "  #  include \"$2\" /* fake */"
  if out=$(bash "$CHECK" "$tmp/t"); then
    echo "FAIL $1 -> $2: not reported"; fails=$((fails + 1))
  elif ! grep -q "layer violation: $1:2 includes \"$2\"" <<<"$out"; then
    echo "FAIL $1 -> $2: wrong report: $out"; fails=$((fails + 1))
  else echo "ok   $1 -> $2 reported"; fi
}

case_ok "clean tree"
case_bad core/mesh/m.c proto/messages.h
case_bad core/admm/sub/a.c server/session.h
case_bad core/common/e.c core/mesh/mesh.h
case_bad proto/p.c core/kelvinlet/kelvinlet.h
case_bad proto/p.c client/dc.h
case_bad proto/p.c proto/wire_core_map.h
case_bad proto/p.c core/admm/admm.h
case_bad client/dc_w.c proto/wire_core_map.h
case_bad client/dc_x.c server/session.h
case_bad client/sub/dc_y.c core/kelvinlet/kelvinlet.h
case_bad client/dc_z.c client/deformctl/ctl.h
case_bad client/deformctl/c.c server/net/conn.h
case_bad server/net/x.c client/dc_client.h
case_bad hid/x.c core/common/df_error.h
case_bad server/hid/hid_x.c core/geom/raycast.h
case_bad server/hid/hid_pen_target.c proto/messages.h
case_bad server/hid/hid_manager.c core/kelvinlet/kelvinlet.h
case_bad server/hid/hid_mgr_drive.c core/geom/raycast.h
case_bad server/hid/hid_class.c proto/messages.h
[ "$fails" -eq 0 ] && echo "check_layers selftest: all cases pass"
[ "$fails" -eq 0 ]
