"""Pipeline: case files, stages, mode selection, diagnose workflow, reports and the CLI."""
