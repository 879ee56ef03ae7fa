#!/usr/bin/env bash
# check_server_cycles.sh [ROOT] — fails (status 1) when the subfolders of server/ include each
# other in a cycle: server/A/x.c including "server/B/y.h" is an edge A -> B, and the edges must
# form no loop (tsort). Files directly in server/ (main, the daemon's start/stop, config, log,
# text: the composition root) are not nodes. Then checks itself: a scratch tree whose net/ and
# session/ include each other must be refused.
set -u
ROOT=${1:-$(cd "$(dirname "$0")/.." && pwd)}

# Prints "A B" for every include edge between two different server subfolders under $1.
edges() {
  (cd "$1" && find server -mindepth 2 \( -name '*.c' -o -name '*.h' \) -type f 2>/dev/null | sort |
    while IFS= read -r f; do
      from=${f#server/}; from=${from%%/*}
      grep -h -E '^[[:space:]]*#[[:space:]]*include[[:space:]]*"server/[^/"]+/' "$f" |
        sed -E 's/^[^"]*"server\/([^/"]+)\/.*/\1/' |
        while IFS= read -r to; do [ "$to" != "$from" ] && echo "$from $to"; done
    done) | sort -u
}

# 0 when the edges of tree $1 form no cycle; prints the loop otherwise.
acyclic() {
  local e out
  e=$(edges "$1")
  [ -z "$e" ] && return 0
  if out=$(echo "$e" | tsort 2>&1 >/dev/null) && [ -z "$out" ]; then return 0; fi
  echo "$out" | sed 's/^tsort: -: //'
  echo "edges: $(echo "$e" | tr '\n' ';')"
  return 1
}

status=0
if ! acyclic "$ROOT"; then
  echo "check_server_cycles: the server/ subfolders include each other in a cycle"
  status=1
else
  echo "check_server_cycles: server/ subfolders: $(edges "$ROOT" | wc -l) include edge(s), no cycle"
fi

scratch=$(mktemp -d); trap 'rm -rf "$scratch"' EXIT
mkdir -p "$scratch/server/net" "$scratch/server/session" "$scratch/server/exec"
printf '#include "server/session/s.h"\n' > "$scratch/server/net/n.c"
printf '#include "server/net/n.h"\n' > "$scratch/server/exec/e.c"
printf '#include "server/exec/e.h"\n' > "$scratch/server/session/s.c"
if acyclic "$scratch" >/dev/null; then
  echo "check_server_cycles: self-test FAILED: a net -> session -> exec -> net loop went unseen"
  status=1
fi
exit $status
