#!/usr/bin/env bash
# One entry point for people and CI.  Each command creates the environment first.
#   bash run.sh main    set up, simulate a named scene, run the benchmarks
#   bash run.sh test    set up, check exercises/ is in sync, run the whole test suite
#   bash run.sh setup   only create .venv and install the pinned dependencies
#   bash run.sh bench   only the benchmarks (add --quick for a short run)
set -euo pipefail
cd "$(dirname "$0")"
VENV=.venv
PY="$VENV/bin/python"

system_packages() {
    # bubblewrap isolates student code in the grader (see grader/sandbox.py).
    if ! command -v bwrap >/dev/null 2>&1; then
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
            (apt-get install -y -qq bubblewrap >/dev/null 2>&1 ||
                (apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq bubblewrap >/dev/null 2>&1)) ||
                echo "warning: could not install bubblewrap; the grader falls back to weaker isolation" >&2
        else
            echo "warning: bubblewrap (bwrap) is not installed; the grader falls back to weaker isolation" >&2
        fi
    fi
}

setup() {
    system_packages
    if [ ! -x "$PY" ]; then
        python3 -m venv "$VENV"
    fi
    local stamp="$VENV/.installed-$(sha1sum pyproject.toml | cut -c1-12)"
    if [ ! -f "$stamp" ]; then
        "$PY" -m pip install --quiet --upgrade pip
        "$PY" -m pip install --quiet -e ".[dev]"
        rm -f "$VENV"/.installed-*
        touch "$stamp"
    fi
}

command="${1:-main}"
shift || true
case "$command" in
    setup) setup ;;
    main)
        setup
        "$PY" -m tools.demo "$@"
        "$PY" bench/run_all.py --quick
        ;;
    bench)
        setup
        "$PY" bench/run_all.py "$@"
        ;;
    test)
        setup
        "$PY" -m tools.generate_exercises --check
        "$PY" -m pytest -n 2 --doctest-modules solutions tools tests "$@"
        ;;
    *)
        echo "unknown command '$command': use main, test, setup or bench" >&2
        exit 2
        ;;
esac
