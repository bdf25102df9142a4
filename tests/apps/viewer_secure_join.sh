#!/bin/sh
# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: 2026 pliant contributors
# `pliant view HOST:PORT --key-file K` joins a host that has the same key (it joined only
# unencrypted masters before), and without the key says what is missing. Usage:
#   viewer_secure_join.sh PLIANT WITH_XVFB DIR
# Exit 0 when both hold, 77 (skipped) when the host cannot bind its port, 1 otherwise.
set -u
exe=$1
xvfb=$2
dir=$3
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
head -c 32 /dev/urandom > session.key && chmod 600 session.key
# A port below the OS's ephemeral range (32768-), by process id, as the session tests choose.
port=$((20000 + $$ % 12000))
("$exe" host --level 3 --port "$port" --duration 30 --key-file session.key > host.log 2>&1
 echo $? > host.rc) &
host=$!
sleep 1
if grep -q bind host.log; then
    cat host.log
    wait "$host"
    exit 77
fi
timeout 60 sh "$xvfb" "$exe" view "127.0.0.1:$port" --key-file session.key --exit-after 1 \
    > keyed.log 2>&1
keyed=$?
timeout 60 sh "$xvfb" "$exe" view "127.0.0.1:$port" --exit-after 1 > plain.log 2>&1
plain=$?
kill "$host" 2>/dev/null
wait "$host"
status=0
if [ "$keyed" -ne 0 ] || ! grep -q "view: joined 127.0.0.1:$port as a viewer" keyed.log; then
    echo "with the key: exit $keyed" && cat keyed.log
    status=1
fi
if [ "$plain" -ne 1 ] ||
    ! grep -q "the master seemingly has a --passphrase or --key-file and this peer none" plain.log
then
    echo "without the key: exit $plain" && cat plain.log
    status=1
fi
[ "$status" -eq 0 ] && echo "the viewer joined with the key and was refused without it"
exit "$status"
