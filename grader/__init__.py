"""The course autograder: student checks, class grading, reports, Gradescope export."""
