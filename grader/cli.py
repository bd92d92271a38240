"""The ``grader`` command.

    grader check [EXERCISE] [--package PATH]      students: public tests of one exercise
    grader update NEW_RELEASE [--dry-run]          students: take a corrected release, keeping their work
    grader grade SUBMISSIONS... --out DIR          instructors: a whole class
    grader gradescope-zip [--out FILE]             the same grading packaged for Gradescope
    grader example-class --out DIR                 write the bundled example class
    grader similarity SUBMISSIONS... --out DIR     flag nearly identical code (pairs, and the reference)
    grader list                                    the tests, their points and visibility
"""
from __future__ import annotations

import argparse
import importlib
import sys
from .harness.results_model import points
from .student.check import in_student_edition

#: subcommand -> (module, add-arguments function, main function, help)
SUBCOMMANDS = {
    "check": ("grader.student.check", "add_check_arguments", "main_check", "run the public tests of an exercise"),
    "grade": ("grader.batch.grade", "add_grade_arguments", "main_grade", "grade a class of submissions"),
    "gradescope-zip": ("grader.release.gradescope", "add_gradescope_arguments", "main_gradescope_zip",
                       "build autograder.zip for Gradescope"),
    "example-class": ("grader.samples.example_class", "add_example_class_arguments", "main_example_class",
                      "write the bundled example class of submissions"),
    "similarity": ("grader.batch.similarity", "add_similarity_arguments", "main_similarity", "flag nearly identical code"),
    "submit": ("grader.student.submit", "add_submit_arguments", "main_submit", "write the zip to hand in (with a manifest)"),
    "update": ("grader.student.update", "add_update_arguments", "main_update",
               "take a corrected release of the course into this folder, keeping your work"),
    "release": ("grader.release.edition", "add_release_arguments", "main_release",
                "write the student edition and the Gradescope autograder"),
}


def list_tests(args) -> int:
    from .harness.run import load_spec  # deferred: pytest, heavy to import

    tests = load_spec()
    width = max(len(t.name) for t in tests)
    for test in tests:
        print(f"{test.name:{width}s}  {test.exercise:9s} {test.points:4g} pt  {test.visibility:16s} {test.title}")
    print(f"{len(tests)} tests, {points(sum(t.points for t in tests))} points")
    return 0


def build_parser() -> argparse.ArgumentParser:

    # The student edition's README teaches `bash run.sh check`: usage lines say so.
    parser = argparse.ArgumentParser(prog="bash run.sh" if in_student_edition() else "grader",
                                     description="Autograder of the collision course.")
    commands = parser.add_subparsers(dest="command", required=True)
    for name, (module_name, add_arguments, main_name, help_text) in SUBCOMMANDS.items():
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name != module_name and not module_name.startswith(f"{exc.name}."):
                raise   # the module is there but something it imports is not: a real error
            continue  # not in this copy (the student edition holds the student commands only)
        sub = commands.add_parser(name, help=help_text, description=help_text)
        getattr(module, add_arguments)(sub)
        sub.set_defaults(handler=getattr(module, main_name))
    commands.add_parser("list", help="list the tests").set_defaults(handler=list_tests)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args) or 0)
    except KeyboardInterrupt:
        print("interrupted: what was graded is kept; rerun the same command to finish", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
