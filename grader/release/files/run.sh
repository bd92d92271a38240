#!/usr/bin/env bash
# The collision course: your course folder.  Every command sets the folder up first.
#   bash run.sh setup              create .venv with the course's packages (quick when done)
#   bash run.sh check [EXERCISE]   run the public tests on your exercises/ package
#   bash run.sh lab                open the chapters (book/) in JupyterLab
#   bash run.sh submit [OPTIONS]   write the zip to hand in (--check runs the tests first)
#   bash run.sh update NEW_RELEASE take a corrected release (folder or zip), keeping your work
set -euo pipefail
CALLED_FROM="$PWD"   # NEW_RELEASE of `update` is relative to where run.sh was called
cd "$(dirname "$0")"
VENV=.venv
PY="$VENV/bin/python"
PYTHON="${PYTHON:-python3}"
KERNEL=collision-course
KERNEL_DISPLAY_NAME="Python (collision-course)"

# A .venv whose Python no longer runs (a system Python upgraded or removed under it: its
# bin/python is a dangling link) is made again; a .venv that is not a virtual environment
# is left alone.
stale_venv() {
    [ -e "$VENV" ] || [ -L "$VENV" ] || return 0
    "$PY" -c '' >/dev/null 2>&1 && return 0
    if [ ! -f "$VENV/pyvenv.cfg" ]; then
        echo "run.sh: $VENV is here but is not a virtual environment (no $VENV/pyvenv.cfg);" >&2
        echo "        move it away (mv $VENV $VENV.old) and run the command again" >&2
        exit 2
    fi
    local was
    was="$(readlink "$PY" 2>/dev/null || true)"
    echo "run.sh: the Python of $VENV no longer runs${was:+ ($PY -> $was is gone)}," \
        "probably after a system Python upgrade: making $VENV again"
    rm -rf "$VENV"
}

# pip in the course's venv; pip itself is not byte-compiled (it runs only in setup: 5 MiB less).
quiet_pip() {
    PYTHONDONTWRITEBYTECODE=1 "$PY" -m pip --quiet --disable-pip-version-check "$@"
}

setup() {
    stale_venv
    if [ ! -x "$PY" ]; then
        if ! command -v "$PYTHON" >/dev/null 2>&1; then
            echo "run.sh: $PYTHON not found: install Python 3.11 or newer (or set PYTHON=...)" >&2
            exit 2
        fi
        if ! "$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
            echo "run.sh: the course needs Python 3.11 or newer; $PYTHON is $("$PYTHON" -V 2>&1)" >&2
            echo "        install a newer one and run: PYTHON=python3.12 bash run.sh setup" >&2
            exit 2
        fi
        echo "creating $VENV ..."
        "$PYTHON" -m venv "$VENV" || {
            echo "run.sh: could not create $VENV (on Debian or Ubuntu: sudo apt install python3-venv)" >&2
            rm -rf "$VENV"
            exit 2
        }
    fi
    local stamp
    stamp="$VENV/.installed-$("$PY" -c 'import hashlib; print(hashlib.sha1(open("pyproject.toml", "rb").read()).hexdigest()[:12])')"
    if [ ! -f "$stamp" ]; then
        echo "installing the course's packages into $VENV (a few minutes the first time) ..."
        # pip's and setuptools' chatter goes to a log, shown only when the install fails.
        # --no-compile: nothing is byte-compiled ahead (pip would compile every module, about
        # 150 MiB); Python caches the modules it imports when they are first used.
        if ! { quiet_pip install --no-compile --upgrade pip &&
               quiet_pip install --no-compile -e . &&
               # The setuptools that Python 3.11's venv adds is never used (pip builds in isolation).
               quiet_pip uninstall --yes setuptools &&
               # Files no one reads (the libraries' test suites, babel's non-English locales ...):
               # the list, with the reason for each, is in grader/student/venv_trim.py.
               "$PY" -m grader.student.venv_trim &&
               "$PY" -m ipykernel install --sys-prefix --name "$KERNEL" --display-name "$KERNEL_DISPLAY_NAME" &&
               "$PY" -m grader.student.notebook quiet-kernel "$VENV/share/jupyter/kernels/$KERNEL/kernel.json" &&
               # The chapters' stored outputs (the reference engine's) shown as trusted in JupyterLab.
               "$VENV/bin/jupyter" trust book/*.ipynb
             } >"$VENV/pip.log" 2>&1; then
            cat "$VENV/pip.log" >&2
            echo "run.sh: installing the course's packages failed (log above, also in $VENV/pip.log)" >&2
            exit 1
        fi
        # JupyterLab: open Markdown pages (book/intro.md ...) rendered, not as source.
        mkdir -p "$VENV/share/jupyter/lab/settings"
        printf '%s\n' '{"@jupyterlab/docmanager-extension:plugin": {"defaultViewers": {"markdown": "Markdown Preview"}}}' \
            > "$VENV/share/jupyter/lab/settings/overrides.json"
        rm -f "$VENV"/.installed-*
        touch "$stamp"
        echo "ready: bash run.sh check, bash run.sh lab"
    fi
}

command="${1:-help}"
shift || true
case "$command" in
    setup) setup ;;
    check)
        setup
        exec "$VENV/bin/grader" check "$@"
        ;;
    lab)
        setup
        if [ "$(id -u)" = 0 ]; then
            # Jupyter refuses to start as root unless asked; root is usual in Docker and some WSL set-ups.
            echo "run.sh: running as root: starting JupyterLab with --allow-root"
            set -- --allow-root "$@"
        fi
        exec "$VENV/bin/jupyter" lab --ServerApp.root_dir="$PWD" "$@" book/intro.md
        ;;
    submit)
        setup
        if [ -f grader/student/submit.py ]; then
            exec "$VENV/bin/grader" submit "$@"
        fi
        # No submit command in this copy: zip the exercises package.
        "$PY" - <<'PYTHON'
import os, zipfile
with zipfile.ZipFile("submission.zip", "w", zipfile.ZIP_DEFLATED) as archive:
    for root, folders, files in os.walk("exercises"):
        folders[:] = sorted(f for f in folders if f != "__pycache__" and not f.startswith("."))
        for name in sorted(files):
            if not name.endswith(".pyc") and not name.startswith("."):
                archive.write(os.path.join(root, name))
print("wrote submission.zip: hand it in as your instructor says")
PYTHON
        ;;
    update)
        if [ $# -lt 1 ]; then
            echo "usage: bash run.sh update NEW_RELEASE [--dry-run]: the folder (or zip) of the release your instructor handed out" >&2
            exit 2
        fi
        release="$1"
        shift
        case "$release" in
            /*|-*) ;;
            *) release="$CALLED_FROM/$release" ;;
        esac
        setup
        # exec: bash stops reading this file, which the update may replace.
        exec "$VENV/bin/grader" update "$release" "$@"
        ;;
    help|-h|--help)
        sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'
        ;;
    *)
        echo "unknown command '$command': use setup, check [EXERCISE], lab, submit or update NEW_RELEASE" >&2
        exit 2
        ;;
esac
