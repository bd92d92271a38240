#!/usr/bin/env bash
# One entry point for people and CI.  Each command creates the environment first.
#   bash run.sh main    set up, simulate a named scene, run the benchmarks, build the book
#   bash run.sh test    set up, check exercises/ and the book's notebooks are in sync,
#                       run the whole test suite (the book's tests included)
#   bash run.sh setup   only create .venv and install the pinned dependencies, Chromium
#                       and the book's MathJax
#   bash run.sh bench   only the benchmarks (add --quick for a short run)
#   bash run.sh release-check   (root) the Gradescope autograder built by its own setup.sh
#                       in a fresh Debian root file system, grading three submissions two
#                       ways in (bubblewrap, and the plain fallback); about 2 minutes
set -euo pipefail
cd "$(dirname "$0")"
VENV=.venv
PY="$VENV/bin/python"

system_packages() {
    # bubblewrap isolates student code in the grader (see grader/sandbox/process.py).
    if ! command -v bwrap >/dev/null 2>&1; then
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
            (apt-get install -y -qq bubblewrap >/dev/null 2>&1 ||
                (apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq bubblewrap >/dev/null 2>&1)) ||
                echo "warning: could not install bubblewrap; the grader falls back to weaker isolation" >&2
        else
            echo "warning: bubblewrap (bwrap) is not installed; the grader falls back to weaker isolation" >&2
        fi
    fi
    # The book: Chromium renders the built pages in a test; npm vendors MathJax once.
    apt_package chromium chromium "the book's browser test will be skipped"
    apt_package npm npm "the book's MathJax cannot be vendored (math would need a CDN)"
}

# apt_package COMMAND PACKAGE CONSEQUENCE: install PACKAGE if COMMAND is missing (root only).
apt_package() {
    command -v "$1" >/dev/null 2>&1 && return 0
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        (apt-get install -y -qq "$2" >/dev/null 2>&1 ||
            (apt-get update -qq >/dev/null 2>&1 && apt-get install -y -qq "$2" >/dev/null 2>&1)) ||
            echo "warning: could not install $2; $3" >&2
    else
        echo "warning: $1 is not installed (apt-get install $2); $3" >&2
    fi
}

setup() {
    system_packages
    if [ ! -x "$PY" ]; then
        python3 -m venv "$VENV"
    fi
    local stamp="$VENV/.installed-$(sha1sum pyproject.toml | cut -c1-12)"
    if [ ! -f "$stamp" ]; then
        # pip's and setuptools' chatter goes to a log, shown only when the install fails.
        if ! { "$PY" -m pip install --quiet --upgrade pip &&
               "$PY" -m pip install --quiet -e ".[dev,book,bench]"; } >"$VENV/pip.log" 2>&1; then
            cat "$VENV/pip.log" >&2
            echo "setup: installing the pinned packages failed (log above, also in $VENV/pip.log)" >&2
            exit 1
        fi
        rm -f "$VENV"/.installed-*
        touch "$stamp"
    fi
    # MathJax from npm into book/_vendor, the book's Jupyter kernel: quiet once done.
    "$PY" -m tools.book setup
}

command="${1:-main}"
shift || true
case "$command" in
    setup) setup ;;
    main)
        setup
        "$PY" -m tools.demo "$@"
        "$PY" bench/run_all.py --quick
        # The bundled example class: reference, stubs and the classic bugs, graded.
        "$PY" -m grader example-class --out out/example-class >/dev/null
        "$PY" -m grader grade out/example-class/* --out out/grades --jobs 2
        echo "class report: $(pwd)/out/grades/class_report.html (one report.html per submission beside it)"
        "$PY" -m tools.book build     # strict (-W -n --keep-going); prints where the HTML is
        ;;
    bench)
        setup
        "$PY" bench/run_all.py "$@"
        ;;
    test)
        setup
        "$PY" -m grader.release.exercises --check
        "$PY" -m tools.book check
        # --dist loadgroup: the book's tests share one build on one worker.
        # COURSE_RELEASE_VENV=1: the student edition's set-up command is run into a fresh
        # venv (tests/test_student_fresh_venv.py; it downloads the pinned packages once, then pip's cache).
        COURSE_RELEASE_VENV="${COURSE_RELEASE_VENV:-1}" \
            "$PY" -m pytest -n 2 --dist loadgroup --doctest-modules solutions tools tests "$@"
        ;;
    release-check)
        setup
        "$PY" -m tools.release_check "$@"
        ;;
    *)
        echo "unknown command '$command': use main, test, setup, bench or release-check" >&2
        exit 2
        ;;
esac
