"""The docs refresher behind `tools/refresh_docs.py`: every generated block of README.md and
docs/, the commands that make it and how their output becomes Markdown."""
