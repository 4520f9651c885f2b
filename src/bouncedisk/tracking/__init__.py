"""Experiment tracking on MLflow.

The store, what is extracted from output files, writing (a command's run; one parent run per
pipeline, nested per job) and reading (``bouncedisk runs``).
"""
