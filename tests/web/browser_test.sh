#!/usr/bin/env bash
# The browser client against the real services: development certificates, a
# data root with cuboid A in alice's folder and a file in bob's, a
# crackvis-data configuration with users alice and bob (passwords, each
# limited to their folder) and crackvis-render's own certificate user, then
# crackvis-data and crackvis-render (with --web-listen on a free port and the
# page from the build tree), and browser.test.mjs in headless Chromium.
# Screenshots and the services' logs stay in BUILD_DIR/tests/web/artefacts/.
#
#   tests/web/browser_test.sh BUILD_DIR SOURCE_DIR
#   CRACKVIS_CHROMIUM=/path/to/chromium tests/web/browser_test.sh ...   (default /usr/bin/chromium)
set -euo pipefail

if (($# != 2)); then
  echo "usage: browser_test.sh BUILD_DIR SOURCE_DIR" >&2
  exit 2
fi
build=$(cd "$1" && pwd)
source=$(cd "$2" && pwd)
artefacts=$build/tests/web/artefacts
chromium=${CRACKVIS_CHROMIUM:-/usr/bin/chromium}

say() { echo "browser_test: $*"; }
die() { echo "browser_test: $*" >&2; exit 1; }

data_server=$build/dataservice/crackvis-data
render_server=$build/server/app/crackvis-render
crackvis=$build/tools/crackvis
# ctest passes where the page was built (web/CMakeLists.txt's CRACKVIS_WEB_DIST).
dist=${CRACKVIS_WEB_DIST:-$build/web/dist}
node_modules=$(dirname "$dist")/node_modules
for program in "$data_server" "$render_server" "$crackvis"; do
  [[ -x $program ]] || die "$program is missing (build crackvis-data, crackvis-render, crackvis)"
done
[[ -f $dist/index.html && -f $dist/app.js ]] || die "$dist has no page (build crackvis-web)"
[[ -d $node_modules/playwright-core ]] || die "$node_modules lacks playwright-core (build crackvis-web)"
[[ -x $chromium ]] || die "no browser at $chromium (apt-get install chromium, or CRACKVIS_CHROMIUM=...)"
command -v node >/dev/null || die "node is not on PATH"

work=$(mktemp -d "${TMPDIR:-/tmp}/crackvis-web-test.XXXXXX")
pids=()
stop_services() {
  local pid
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
  cp "$work"/*.log "$artefacts"/ 2>/dev/null || true
  rm -rf "$work"
}
trap stop_services EXIT
rm -rf "$artefacts"
mkdir -p "$artefacts"

# Certificates: the server's (SANs localhost, 127.0.0.1) serves the page too;
# crackvis-render reads from crackvis-data with its own.
certs=$work/certs
bash "$source/certs/make-dev-certs.sh" "$certs" --client crackvis-render >/dev/null

root=$work/data
mkdir -p "$root/alice" "$root/bob"
"$crackvis" sim cuboid3d --set A --scale 0.3 --quiet -o "$root/alice/cuboidA.h5"
cp "$root/alice/cuboidA.h5" "$root/bob/cuboidB.h5"
# A name with markup in it: the page must show it as text.
markup_name='<img src=x onerror="window.crackvisPwned=1">.h5'
cp "$root/alice/cuboidA.h5" "$root/alice/$markup_name"

alice_password=$(openssl rand -hex 12)
bob_password=$(openssl rand -hex 12)
hash() { printf %s "$1" | "$data_server" hash-secret; }
config=$work/data.json
cat >"$config" <<JSON
{
  "users": [
    {"name": "alice", "password_hash": "$(hash "$alice_password")", "folders": ["alice"]},
    {"name": "bob", "password_hash": "$(hash "$bob_password")", "folders": ["bob"]},
    {"name": "render", "certificate_name": "crackvis-render", "folders": ["*"]}
  ]
}
JSON

# The address a service printed, e.g. 'event=serving address="127.0.0.1:PORT"'.
await_address() {
  local log=$1 event=$2 pid=$3 address
  for _ in $(seq 1 600); do
    address=$(grep -o "event=$event address=\"127\.0\.0\.1:[0-9]*\"" "$log" 2>/dev/null | head -1 |
              sed 's/.*address="\(.*\)"/\1/') || true
    if [[ -n $address ]]; then
      echo "$address"
      return 0
    fi
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  echo "browser_test: no event=$event in $log:" >&2
  cat "$log" >&2
  return 1
}

"$data_server" --config "$config" --root "$root" --listen 127.0.0.1:0 \
  --ca "$certs/ca.pem" --cert "$certs/server.pem" --key "$certs/server.key" \
  --access-log "$work/data-access.log" >"$work/crackvis-data.log" 2>&1 &
pids+=($!)
data_address=$(await_address "$work/crackvis-data.log" serving "${pids[-1]}")

"$render_server" --listen 127.0.0.1:0 \
  --ca "$certs/ca.pem" --cert "$certs/server.pem" --key "$certs/server.key" \
  --data-server "localhost:${data_address##*:}" --data-ca "$certs/ca.pem" \
  --data-cert "$certs/crackvis-render.pem" --data-key "$certs/crackvis-render.key" \
  --users-from "$config" --web-listen 127.0.0.1:0 --web-root "$dist" \
  --access-log "$work/render-access.log" >"$work/crackvis-render.log" 2>&1 &
pids+=($!)
web_address=$(await_address "$work/crackvis-render.log" web_serving "${pids[-1]}")
say "crackvis-data on $data_address, the page on https://$web_address/"

CRACKVIS_WEB_URL="https://$web_address/" \
CRACKVIS_CA="$certs/ca.pem" \
CRACKVIS_USER=alice \
CRACKVIS_PASSWORD="$alice_password" \
CRACKVIS_FILE=alice/cuboidA.h5 \
CRACKVIS_FOREIGN_FILE=bob/cuboidB.h5 \
CRACKVIS_MARKUP_FILE="alice/$markup_name" \
CRACKVIS_ARTEFACTS="$artefacts" \
CRACKVIS_CLI="$crackvis" \
CRACKVIS_DATA_ROOT="$root" \
CRACKVIS_NODE_MODULES="$node_modules" \
CRACKVIS_CHROMIUM="$chromium" \
  node "$source/tests/web/browser.test.mjs"
