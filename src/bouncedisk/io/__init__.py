"""Files: what is read and written.

The engine's records named, netCDF writing (streamed, atomic) and reading, provenance keys,
output checks, measured curves, job logs.
"""
