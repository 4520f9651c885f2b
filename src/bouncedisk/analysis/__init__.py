"""Analyses: what a run or an ensemble shows.

Observables, ensembles, statistics with intervals, bands, sweeps and continuation, Poincaré
maps.
"""
