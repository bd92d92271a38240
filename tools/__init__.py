"""Maintenance tools of the course: the exercise generator and the demo."""
