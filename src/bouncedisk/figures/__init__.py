"""Figures: one module per family, each figure a pure function of Datasets.

:mod:`.registry` declares them (standard library only: the Snakefile reads it), :mod:`.drawing`
opens their inputs and draws. Importing this package imports no matplotlib.
"""
