"""Analysis jobs between the numerical core and the front ends, one module per job.

Each module imports only what its job needs (the core's numpy/scipy modules), so that a light job
such as ``linecheck check`` does not load the solvers.  Nothing here prints.
"""
