# Sourced by the shell tests: check NAME CONDITION prints ok/FAIL and remembers a failure in $fail.
fail=0
check() { if ! eval "$2"; then echo "FAIL: $1"; fail=1; else echo "ok: $1"; fi; }
