"""``bash run.sh release-check``: Gradescope's autograder tried in a fresh Debian image.

Gradescope builds an image from Ubuntu 22.04 by unpacking ``autograder.zip`` into
``/autograder/source`` and running ``setup.sh`` as root; then, for each submission, it
runs ``/autograder/run_autograder``.  This does the same in a minimal Debian root file
system made by ``debootstrap`` (only Debian's archive is reachable from here): nothing
of this machine's Python or packages is in it.  Root only.

1. ``debootstrap --variant=minbase bookworm`` into ``OUT/debian-bookworm`` (kept and
   reused; ``--fresh`` makes it again), copied into ``OUT/image``;
2. the archive built from this checkout, unpacked as Gradescope does, and ``setup.sh``
   run inside the image (apt and pip download from Debian's archive and PyPI);
3. three submissions graded inside the image -- the reference (full marks), the stubs
   (0) and a student's zip (two exercise files solved) -- two ways in:

   - ``bwrap``: the image entered with bubblewrap (a mount namespace and pivot_root,
     as a container runtime does), so the grader's own bubblewrap sandbox works;
   - ``plain``: the image entered with ``chroot``, where the kernel refuses new user
     namespaces (as a container without those rights does): the grader falls back to
     plain isolation and must still give the reference full marks.

   The student's zip must score what local grading (this checkout's venv) gives it.

Exit status 0 when every grade is as expected, 1 otherwise, 2 when it cannot run.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from contextlib import contextmanager
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SUITE = "bookworm"
MIRROR = "http://deb.debian.org/debian"
#: Exercise files the sample student has solved (the rest are still the stubs).
SOLVED = ("broadphase/uniform_grid.py", "response/momentum_1d.py")
WAYS = ("bwrap", "plain")
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")


class CheckError(RuntimeError):
    """The check cannot run here (not root, no debootstrap...): the message says why."""


def run(command: list[str], **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run(command, check=True, **kwargs)


def base_rootfs(out: Path, fresh: bool) -> Path:
    """A minimal Debian root file system, made once by debootstrap and kept."""
    base = out / f"debian-{SUITE}"
    if fresh and base.exists():
        shutil.rmtree(base)
    if (base / "etc" / "debian_version").is_file() and not (base / "debootstrap").exists():
        return base
    if shutil.which("debootstrap") is None:
        subprocess.run(["apt-get", "install", "-y", "-qq", "debootstrap"], stdout=subprocess.DEVNULL)
    if shutil.which("debootstrap") is None:
        raise CheckError("debootstrap is not installed and apt-get could not install it")
    shutil.rmtree(base, ignore_errors=True)
    started = time.perf_counter()
    print(f"debootstrap --variant=minbase {SUITE} {base} ...", flush=True)
    run(["debootstrap", "--variant=minbase", SUITE, str(base), MIRROR], stdout=subprocess.DEVNULL)
    print(f"  {time.perf_counter() - started:.0f} s", flush=True)
    return base


def make_image(base: Path, out: Path, archive: Path) -> Path:
    """A copy of the base with the archive where Gradescope puts it."""
    image = out / "image"
    if image.exists():
        shutil.rmtree(image)
    run(["cp", "-a", str(base), str(image)])
    source = image / "autograder" / "source"
    source.mkdir(parents=True)
    with zipfile.ZipFile(archive) as handle:
        for info in handle.infolist():   # extractall drops the executable bits
            handle.extract(info, source)
            mode = (info.external_attr >> 16) & 0o777
            if mode:
                os.chmod(source / info.filename, mode)
    shutil.copy2(source / "run_autograder", image / "autograder" / "run_autograder")
    shutil.copy2("/etc/resolv.conf", image / "etc" / "resolv.conf")   # apt and pip reach the network
    machine_network_settings(image)
    return image


def machine_network_settings(image: Path) -> None:
    """This machine's way to the package index, which Gradescope's machines do not need:
    the certificates it trusts beyond Debian's (an egress proxy's CA: setup.sh's
    ``ca-certificates`` adds them to the system bundle) and pip's settings naming that
    bundle."""
    local = Path("/usr/local/share/ca-certificates")
    if local.is_dir():
        shutil.copytree(local, image / local.relative_to("/"), dirs_exist_ok=True)
    if Path("/etc/pip.conf").is_file():
        shutil.copy2("/etc/pip.conf", image / "etc" / "pip.conf")


@contextmanager
def mounted(image: Path):
    """/proc, /dev and /sys of the host in the image (for the chroot way in)."""
    targets = []
    locks = uid_locks()
    try:
        for kind, source, target, options in (("proc", "proc", "proc", []), ("bind", "/dev", "dev", []),
                                              ("bind", "/sys", "sys", ["-o", "ro"]),
                                              ("bind", str(locks), str(locks).lstrip("/"), [])):
            path = image / target
            path.mkdir(parents=True, exist_ok=True)
            if kind == "proc":
                run(["mount", "-t", "proc", "proc", str(path)])
            else:
                run(["mount", "--rbind", *options, source, str(path)])
                run(["mount", "--make-rslave", str(path)])
            targets.append(path)
        yield
    finally:
        for path in reversed(targets):
            subprocess.run(["umount", "-R", "-l", str(path)], stderr=subprocess.DEVNULL)


def uid_locks() -> Path:
    """This machine's registry of sandbox users (grader.sandbox.process), shared with the image:
    its processes are this machine's, and a grader outside (a test run, a batch) that
    did not see the image's locks would take its sandboxes' users for strays and kill
    them."""
    from grader.sandbox.process import uid_lock_folder

    folder = uid_lock_folder()
    if folder is None:
        raise CheckError("no safe folder for the sandbox users' locks here (see grader.sandbox.process.uid_lock_folder)")
    return folder


def inside(image: Path, way: str, script: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    """Run ``bash -c script`` as root inside the image, entered ``way`` (bwrap or chroot)."""
    variables = {"PATH": "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin", "HOME": "/root",
                 "LANG": "C.UTF-8", **(env or {})}
    exports = " ".join(f"{k}={json.dumps(v)}" for k, v in variables.items())
    command = ["bash", "-c", f"export {exports}; {script}"]
    if way == "bwrap":
        # A mount namespace with the image as its root (pivot_root, as container runtimes
        # do): the grader's own bubblewrap can then make its sandboxes inside.
        entry = ["bwrap", "--cap-add", "ALL", "--bind", str(image), "/", "--proc", "/proc", "--dev", "/dev",
                 "--ro-bind", "/sys", "/sys", "--tmpfs", "/tmp", "--bind", str(uid_locks()), str(uid_locks()),
                 "--die-with-parent", "--", "env", "-i"]
        return subprocess.run(entry + command, capture_output=True, text=True)
    with mounted(image):
        return subprocess.run(["chroot", str(image), "env", "-i"] + command, capture_output=True, text=True)


def submissions(folder: Path) -> dict[str, Path]:
    """The reference and the stubs (folders) and a student's zip written by `grader submit`."""
    from grader.student.submit import write_submission

    shutil.copytree(REPO / "solutions", folder / "reference" / "exercises", ignore=IGNORE)
    shutil.copytree(REPO / "exercises", folder / "stubs" / "exercises", ignore=IGNORE)
    student = folder / "student-copy" / "exercises"
    shutil.copytree(REPO / "exercises", student, ignore=IGNORE)
    for name in SOLVED:
        shutil.copyfile(REPO / "solutions" / name, student / name)
    return {"reference": folder / "reference", "stubs": folder / "stubs",
            "student": write_submission(student, folder / "student.zip", name="student").path}


def place(submission: Path, target: Path) -> None:
    """Put a submission where Gradescope does (a zip unpacked, as an upload is)."""
    shutil.rmtree(target, ignore_errors=True)
    if submission.suffix == ".zip":
        with zipfile.ZipFile(submission) as handle:
            handle.extractall(target)
    else:
        shutil.copytree(submission, target, ignore=IGNORE)


def by_test(data: dict) -> dict[str, tuple[str, float]]:
    return {t["extra_data"]["test"]: (t["extra_data"]["status"], t["score"]) for t in data["tests"]}


def check(out: Path, fresh: bool, ways: tuple[str, ...]) -> int:
    from grader.batch.grade import grade_submissions
    from grader.release.gradescope import build_autograder_zip

    if os.geteuid() != 0:
        raise CheckError("release-check needs root (debootstrap, chroot and setup.sh as Gradescope runs it)")
    for tool in ("bwrap", "chroot", "mount"):
        if shutil.which(tool) is None:
            raise CheckError(f"{tool} is not installed")
    out.mkdir(parents=True, exist_ok=True)
    timings: dict[str, float] = {}
    started = time.perf_counter()
    base = base_rootfs(out, fresh)
    timings["debian root file system"] = time.perf_counter() - started

    archive = build_autograder_zip(out / "autograder.zip")
    image = make_image(base, out, archive)
    print(f"setup.sh in the image (apt-get and pip, as root) ...", flush=True)
    started = time.perf_counter()
    setup = inside(image, "bwrap", "cd /autograder/source && bash ./setup.sh")
    timings["setup.sh"] = time.perf_counter() - started
    (out / "setup.log").write_text(setup.stdout + setup.stderr)
    if setup.returncode != 0:
        print(f"setup.sh failed (exit {setup.returncode}); its output is in {out / 'setup.log'}:\n"
              + (setup.stdout + setup.stderr)[-3000:], flush=True)
        return 1
    print(f"  {timings['setup.sh']:.0f} s; " + (setup.stdout.strip().splitlines() or [""])[-1], flush=True)

    with tempfile.TemporaryDirectory(prefix="release-check-") as scratch:
        samples = submissions(Path(scratch))
        local_rows = grade_submissions(list(samples.values()), Path(scratch) / "local", jobs=1, progress=False,
                                       html=False)
        local = {name: row["results"] for name, row in zip(samples, local_rows)}
        failures = []
        print(f"{'way in':8s} {'submission':11s} {'score':>9s}  {'local':>9s}  isolation  seconds")
        for way in ways:
            for name, submission in samples.items():
                place(submission, image / "autograder" / "submission")
                shutil.rmtree(image / "autograder" / "results", ignore_errors=True)
                started = time.perf_counter()
                completed = inside(image, way, "cd /autograder && ./run_autograder")
                seconds = time.perf_counter() - started
                timings[f"grade {name} ({way})"] = seconds
                results = image / "autograder" / "results" / "results.json"
                data = json.loads(results.read_text()) if results.exists() else None
                kept = out / "results" / f"{way}-{name}"
                kept.mkdir(parents=True, exist_ok=True)
                (kept / "run_autograder.log").write_text(completed.stdout + completed.stderr)
                if data is not None:
                    shutil.copy2(results, kept / "results.json")
                expected = local[name]
                if data is None:
                    failures.append(f"{way}/{name}: no results.json (exit {completed.returncode}):\n"
                                    + (completed.stdout + completed.stderr)[-2000:])
                    print(f"{way:8s} {name:11s} {'-':>9s}  {expected['score']:>9g}  -          {seconds:.0f}")
                    continue
                isolation = (data.get("extra_data") or {}).get("isolation", "?")
                print(f"{way:8s} {name:11s} {data['score']:>9g}  {expected['score']:>9g}  {isolation:9s}  "
                      f"{seconds:.0f}", flush=True)
                if by_test(data) != by_test(expected):
                    differ = sorted(t for t, v in by_test(data).items() if by_test(expected).get(t) != v)
                    failures.append(f"{way}/{name}: differs from local grading on {', '.join(differ[:8])}")
                if isolation != way:
                    failures.append(f"{way}/{name}: graded with {isolation} isolation, expected {way}")
                if name == "reference" and data["score"] != data["max_score"]:
                    failures.append(f"{way}/{name}: {data['score']:g} of {data['max_score']:g}, not full marks")
                if name == "stubs" and data["score"] != 0:
                    failures.append(f"{way}/{name}: {data['score']:g}, not 0")
    print("timings: " + ", ".join(f"{k} {v:.0f} s" for k, v in timings.items()))
    if failures:
        print("release-check FAILED:\n  " + "\n  ".join(failures))
        return 1
    print(f"release-check passed: the image built by setup.sh grades like local grading "
          f"({', '.join(ways)}); image in {image}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="bash run.sh release-check", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out/release-check", type=Path, metavar="DIR",
                        help="where the root file systems and the archive go (default: %(default)s)")
    parser.add_argument("--fresh", action="store_true", help="debootstrap the base again")
    parser.add_argument("--way", choices=WAYS, action="append", help="only this way in (default: both)")
    args = parser.parse_args(argv)
    try:
        return check(args.out.resolve(), args.fresh, tuple(args.way or WAYS))
    except CheckError as exc:
        print(f"release-check: {exc}", file=sys.stderr)
        return 2
    except subprocess.CalledProcessError as exc:
        print(f"release-check: {' '.join(map(str, exc.cmd))} failed (exit {exc.returncode})", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
