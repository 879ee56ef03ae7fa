#!/usr/bin/env bash
# demo_run.sh — what `make run` executes after building: a short deformd session end to end.
#
# Starts build/bin/deformd on a temporary Unix socket, loads ../shared/meshes/spot.obj (or, when
# the shared meshes are absent, a 40x40 grid OBJ generated here), applies a Kelvinlet grab and
# a twist through build/bin/deformctl, writes the mesh before and after to $DEMO_OUT
# (default /tmp/deformd-demo/before.obj and after.obj), prints how many vertices moved and by
# how much at most, writes a preview picture (rest | current, shaded by displacement) to
# $DEMO_OUT/preview.png with `deformctl preview` and prints its path, and stops the daemon (also on error or interrupt). Needs no stdin; works
# under CI=true. Environment: BUILD (build dir, default build), MESHES, DEMO_OUT.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
MESHES=${MESHES:-$(pwd)/../shared/meshes}
OUT=${DEMO_OUT:-/tmp/deformd-demo}
DEFORMD=$BUILD/bin/deformd
CTL=$BUILD/bin/deformctl
READY_TRIES=100     # x 0.1 s

for b in "$DEFORMD" "$CTL"; do
  [ -x "$b" ] || { echo "demo: $b is missing (run make first)" >&2; exit 1; }
done

tmp=$(mktemp -d /tmp/deformd-demo-run.XXXXXX)
sock=$tmp/deformd.sock
pid=
cleanup() {
  local rc=$?
  if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null || true
    for _ in $(seq 1 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    if kill -0 "$pid" 2>/dev/null; then
      echo "demo: deformd did not stop, killing it" >&2
      kill -KILL "$pid"
    fi
    wait "$pid" 2>/dev/null || true
  fi
  if [ "$rc" -ne 0 ] && [ -s "$tmp/deformd.log" ]; then
    echo "demo: failed (status $rc); deformd log:" >&2; tail -n 20 "$tmp/deformd.log" >&2
  fi
  rm -rf "$tmp"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

"$DEFORMD" --foreground --socket "$sock" --store none --log-level warn </dev/null >"$tmp/deformd.log" 2>&1 &
pid=$!
ctl() { "$CTL" --socket "$sock" "$@" </dev/null; }
for i in $(seq 1 "$READY_TRIES"); do
  ctl ping >/dev/null 2>&1 && break
  kill -0 "$pid" 2>/dev/null || { echo "demo: deformd exited early" >&2; exit 1; }
  [ "$i" -eq "$READY_TRIES" ] && { echo "demo: deformd not answering on $sock" >&2; exit 1; }
  sleep 0.1
done
echo "demo: deformd (pid $pid) listening on $sock"

mkdir -p "$OUT"
mesh=$MESHES/spot.obj
if [ ! -f "$mesh" ]; then
  mesh=$OUT/grid.obj
  echo "demo: $MESHES/spot.obj not found; generating a 40x40 grid at $mesh"
  awk 'BEGIN { n = 40; print "# deformd demo grid";
    for (j = 0; j < n; j++) for (i = 0; i < n; i++)
      printf "v %.6f %.6f %.6f\n", i / (n - 1), j / (n - 1), 0.1 * sin(3 * i / (n - 1));
    for (j = 0; j < n - 1; j++) for (i = 0; i < n - 1; i++) { a = j * n + i + 1;
      printf "f %d %d %d\nf %d %d %d\n", a, a + 1, a + n + 1, a, a + n + 1, a + n } }' >"$mesh"
fi

sid=$(ctl load "$mesh" --name demo)
echo "demo: loaded $mesh as session $sid"
ctl get "$sid" --out "$OUT/before.obj"

# Brush placement from the mesh itself: grab the vertex with the largest x outward by 15% of
# the bounding-box diagonal (bi-scale, radius 20%), then twist 0.6 rad about +y at the vertex
# of largest y.
read -r gx gy gz ty_x ty_y ty_z diag < <(awk '$1 == "v" {
    n++; x = $2; y = $3; z = $4;
    if (n == 1 || x > gx) { gx = x; gy = y; gz = z }
    if (n == 1 || y > ty) { tx = x; ty = y; tz = z }
    if (n == 1 || x < x0) x0 = x; if (n == 1 || x > x1) x1 = x;
    if (n == 1 || y < y0) y0 = y; if (n == 1 || y > y1) y1 = y;
    if (n == 1 || z < z0) z0 = z; if (n == 1 || z > z1) z1 = z }
  END { printf "%.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", gx, gy, gz, tx, ty, tz,
        sqrt((x1 - x0)^2 + (y1 - y0)^2 + (z1 - z0)^2) }' "$OUT/before.obj")
move=$(awk -v d="$diag" 'BEGIN { printf "%.6f,0,%.6f", 0.15 * d, 0.05 * d }')
radius=$(awk -v d="$diag" 'BEGIN { printf "%.6f", 0.2 * d }')
ctl brush "$sid" --type grab --center "$gx,$gy,$gz" --move "$move" --radius "$radius" --nu 0.45 \
  --falloff 2 --ratio 1.5
echo "demo: bi-scale grab at ($gx, $gy, $gz) by ($move), radius $radius"
ctl brush "$sid" --type twist --center "$ty_x,$ty_y,$ty_z" --twist 0,0.6,0 --radius "$radius" \
  --nu 0.45
echo "demo: twist 0.6 rad about +y at ($ty_x, $ty_y, $ty_z), radius $radius"
ctl get "$sid" --out "$OUT/after.obj"

awk -v diag="$diag" '$1 == "v" { if (FNR == NR) { b[++n] = $2 " " $3 " " $4 } else { m++;
      split(b[m], p, " "); d = sqrt(($2 - p[1])^2 + ($3 - p[2])^2 + ($4 - p[3])^2);
      if (d > 1e-6) moved++; if (d > 0.01 * diag) far++; if (d > mx) mx = d } }
  END { if (m != n) { print "demo: vertex counts differ: " n " vs " m; exit 1 }
        printf "demo: %d of %d vertices moved (%d by more than 1%% of the %.4g bounding-box " \
               "diagonal), at most %.6g mesh units\n", moved, n, far, diag, mx;
        if (moved == 0) exit 1 }' "$OUT/before.obj" "$OUT/after.obj"
echo "demo: before: $OUT/before.obj"
echo "demo: after:  $OUT/after.obj"
ctl preview "$sid" --out "$OUT/preview.png" --view iso >/dev/null
echo "demo: preview (rest | current, coloured by displacement): $OUT/preview.png"
