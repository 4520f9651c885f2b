"""Running a scene: model + engine (or a comparator solver) -> a streamed file.

Provenance and interrupts of a run, and the child process whose memory the scaling study
measures.
"""
