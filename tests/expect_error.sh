#!/bin/sh
# Runs a command that must fail on a bad input: exit status 1 and exactly one line on stderr
# containing the expected text. Usage: expect_error.sh TEXT COMMAND [ARGS...]
expected="$1"
shift
err=$("$@" 2>&1 >/dev/null)
status=$?
lines=$(printf '%s\n' "$err" | wc -l)
if [ "$status" -ne 1 ]; then echo "exit status $status, expected 1: $err"; exit 1; fi
if [ "$lines" -ne 1 ]; then echo "expected one line on stderr, got $lines: $err"; exit 1; fi
case "$err" in
    *"$expected"*) exit 0 ;;
    *) echo "stderr does not name '$expected': $err"; exit 1 ;;
esac
