"""What grading produces (instructors only): Gradescope's results.json, the instructor's
pages (``instructor``) and the student's feedback page (``feedback``)."""
