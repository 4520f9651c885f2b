"""Studies built on the analyses.

Work–precision, scaling, statistics cost, the clipped comparison, torque–speed curves, global
sensitivity, the paper's reproduction checks.
"""
