#!/usr/bin/env bash
# A throw-away PostgreSQL server for the records' tests (issue 28): Debian's `postgresql` (apt,
# non-interactive, when missing), a cluster made by initdb in a temporary folder and run as the
# `postgres` user, listening on 127.0.0.1 only, on a free port; trust authentication for the
# test user `botbench` and password authentication (botbench / botbench-test) for `botbench_pw`.
#
#   bash .ci/postgres.sh start DIR   -> prints the line `BOTBENCH_TEST_POSTGRES=postgres://...`
#   bash .ci/postgres.sh stop DIR
#
# The tests read BOTBENCH_TEST_POSTGRES (the server's URL) and BOTBENCH_TEST_PG_CTL (the
# command that stops and starts it again, for the spool test that kills the server mid-run).
set -euo pipefail

cmd=${1:?start or stop}
dir=${2:?a folder for the cluster}

bin_dir() {
    local v
    v=$(ls /usr/lib/postgresql 2>/dev/null | sort -V | tail -1)
    [ -n "$v" ] && echo "/usr/lib/postgresql/$v/bin"
}

case $cmd in
start)
    if [ -z "$(bin_dir)" ]; then
        echo "installing postgresql (apt)" >&2
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq >&2
        # The package's own cluster is not wanted: ours lives in DIR.
        mkdir -p /etc/postgresql-common
        echo "create_main_cluster = false" >/etc/postgresql-common/createcluster.conf
        apt-get install -y -qq --no-install-recommends -o Dpkg::Options::=--force-confold postgresql >&2
    fi
    bin=$(bin_dir)
    rm -rf "$dir"
    mkdir -p "$dir"
    chown postgres:postgres "$dir"
    # The server runs as `postgres`, which must reach DIR: a folder from `mktemp -d` is
    # root's alone (0700), so every folder above DIR is opened for traversal (x, not read).
    up=$(dirname "$(realpath "$dir")")
    while [ "$up" != / ]; do
        chmod o+x "$up"
        up=$(dirname "$up")
    done
    port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    su postgres -s /bin/sh -c "$bin/initdb -D '$dir/data' -U postgres -A trust --no-sync -E UTF8 >'$dir/initdb.log' 2>&1"
    # Password login for botbench_pw (tests of a refused login), trust for the rest.
    sed -i '1i host all botbench_pw 127.0.0.1/32 scram-sha-256' "$dir/data/pg_hba.conf"
    cat >"$dir/ctl" <<EOF
#!/bin/sh
# stop | start: the test cluster at $dir
exec su postgres -s /bin/sh -c "$bin/pg_ctl -D '$dir/data' -l '$dir/server.log' -w -t 60 -m immediate -o '-c listen_addresses=127.0.0.1 -c port=$port -c unix_socket_directories=$dir -c fsync=off -c synchronous_commit=off -c full_page_writes=off' \$1 >&2"
EOF
    chmod +x "$dir/ctl"
    "$dir/ctl" start >&2
    su postgres -s /bin/sh -c "$bin/psql -q -h 127.0.0.1 -p $port -U postgres -d postgres" >&2 <<EOF
CREATE ROLE botbench LOGIN CREATEDB;
CREATE ROLE botbench_pw LOGIN PASSWORD 'botbench-test';
CREATE DATABASE botbench OWNER botbench;
EOF
    echo "BOTBENCH_TEST_POSTGRES=postgres://botbench@127.0.0.1:$port/botbench"
    echo "BOTBENCH_TEST_PG_CTL=$dir/ctl"
    ;;
stop)
    if [ -x "$dir/ctl" ]; then
        "$dir/ctl" stop >/dev/null 2>&1 || true
    fi
    rm -rf "$dir"
    ;;
*)
    echo "usage: $0 start|stop DIR" >&2
    exit 2
    ;;
esac
