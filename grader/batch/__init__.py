"""Grading a class (instructors only): submissions read and verified, grading worker
processes scheduled over sandbox slots, results and gradebook written, similarity
flagged, time limits calibrated."""
