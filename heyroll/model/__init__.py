"""Model layer: bodies, tracks and collision laws.

Pure functions and frozen dataclasses. Scalars are held as mpmath numbers at
``MODEL_PRECISION`` bits so that every derived constant can be rounded once
to whatever precision the simulation runs in (double, quad, MPFR).
"""
