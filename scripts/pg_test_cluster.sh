#!/usr/bin/env bash
# A throw-away PostgreSQL 15 cluster for tests (Debian's postgresql-15, no system service): run as an unprivileged
# user (`postgres`, else `nobody`, when started as root), trust authentication, a Unix socket and no TCP port unless
# --tcp PORT. Prints the URL and writes it to DIR/url. fsync is off unless --durable (a test cluster loses nothing
# that matters in a crash).
# Usage: scripts/pg_test_cluster.sh start DIR [--tcp PORT] [--durable]   start (or resume) it; idempotent
#        scripts/pg_test_cluster.sh pause DIR     stop the server, keep its data (`start DIR` resumes it, same URL)
#        scripts/pg_test_cluster.sh stop DIR      stop it and remove it; idempotent
set -euo pipefail

bin=/usr/lib/postgresql/15/bin
die() {
  echo "pg_test_cluster: $*" >&2
  exit 1
}
usage() { die "usage: pg_test_cluster.sh start|pause|stop DIR [--tcp PORT] [--durable]"; }

[ $# -ge 2 ] || usage
command=$1
dir=$2
shift 2
tcp_port=""
durable=0
while [ $# -gt 0 ]; do
  case "$1" in
    --tcp)
      [ $# -ge 2 ] || usage
      if ! [[ "$2" =~ ^[0-9]+$ ]] || [ "$2" -lt 1 ] || [ "$2" -gt 65535 ]; then die "--tcp needs a port 1-65535 (got '$2')"; fi
      tcp_port=$2
      shift 2
      ;;
    --durable) durable=1; shift ;;
    *) usage ;;
  esac
done

# Who runs the server: PostgreSQL refuses to run as root.
run_user=""
if [ "$(id -u)" -eq 0 ]; then
  if id postgres >/dev/null 2>&1; then run_user=postgres; else run_user=nobody; fi
fi
as_user() {
  if [ -n "$run_user" ]; then runuser -u "$run_user" -- "$@"; else "$@"; fi
}

# The cluster's folder (data/, the socket, the log): DIR/cluster, or a short folder under /tmp when the socket path
# would pass the 107-byte limit or the server's user cannot reach DIR. DIR/cluster_dir says which.
cluster_dir() {
  if [ -f "$dir/cluster_dir" ]; then cat "$dir/cluster_dir"; fi
}

server_running() {
  local c=$1
  [ -f "$c/data/PG_VERSION" ] && as_user "$bin/pg_ctl" status -D "$c/data" >/dev/null 2>&1
}

start() {
  if [ ! -x "$bin/initdb" ] || [ ! -x "$bin/pg_ctl" ]; then
    die "postgresql-15 is not installed ($bin/initdb missing): run scripts/setup.sh"
  fi
  mkdir -p "$dir"
  dir=$(cd "$dir" && pwd)
  local c
  c=$(cluster_dir)
  if [ -z "$c" ] || [ ! -d "$c" ]; then
    c="$dir/cluster"
    mkdir -p "$c"
    [ -z "$run_user" ] || chown "$run_user" "$c"
    if [ ${#c} -gt 90 ] || ! as_user test -w "$c"; then
      rmdir "$c"
      c=$(mktemp -d /tmp/texwarp-pg.XXXXXX)
      [ -z "$run_user" ] || chown "$run_user" "$c"
      as_user test -w "$c" || die "user ${run_user:-$(id -un)} cannot write $c"
    fi
    echo "$c" >"$dir/cluster_dir"
  fi
  if [ -n "$tcp_port" ]; then echo "$tcp_port" >"$dir/tcp_port"; fi
  if [ -f "$dir/tcp_port" ]; then tcp_port=$(cat "$dir/tcp_port"); fi
  if [ "$durable" = 1 ]; then touch "$dir/durable"; fi
  local url
  if [ -n "$tcp_port" ]; then
    url="postgresql://texwarp@127.0.0.1:$tcp_port/postgres"
  else
    url="postgresql://texwarp@/postgres?host=$c"
  fi
  if ! server_running "$c"; then
    if [ ! -f "$c/data/PG_VERSION" ]; then
      as_user "$bin/initdb" -D "$c/data" -U texwarp --auth=trust -E UTF8 --no-locale --no-sync >"$c/initdb.log" 2>&1 ||
        die "initdb failed (see $c/initdb.log): $(tail -3 "$c/initdb.log")"
    fi
    local listen="''"
    [ -z "$tcp_port" ] || listen="127.0.0.1"
    local fsync=off
    [ ! -f "$dir/durable" ] || fsync=on
    as_user "$bin/pg_ctl" start -D "$c/data" -w -t 60 -l "$c/server.log" \
      -o "-c listen_addresses=$listen -p ${tcp_port:-5432} -k $c -c fsync=$fsync -c max_connections=300" \
      >/dev/null 2>&1 || die "the server did not start (see $c/server.log): $(tail -5 "$c/server.log" 2>/dev/null)"
  fi
  echo "$url" >"$dir/url"
  echo "$url"
}

pause() {
  local c
  c=$(cluster_dir)
  if [ -n "$c" ] && server_running "$c"; then
    as_user "$bin/pg_ctl" stop -D "$c/data" -m fast -w -t 60 >/dev/null
  fi
}

stop() {
  [ -d "$dir" ] || exit 0
  local c
  c=$(cluster_dir)
  if [ -n "$c" ] && [ -d "$c" ]; then
    if server_running "$c"; then as_user "$bin/pg_ctl" stop -D "$c/data" -m immediate -w -t 60 >/dev/null || true; fi
    rm -rf "$c"
  fi
  rm -f "$dir/url" "$dir/cluster_dir" "$dir/tcp_port" "$dir/durable"
  rmdir "$dir" 2>/dev/null || true
}

case "$command" in
  start) start ;;
  pause) pause ;;
  stop) stop ;;
  *) usage ;;
esac
