"""Mathematics with no robot in it: rigid placements and rotations (numeric), spatial algebra and
linear algebra on CasADi SX, and the one place where numbers are compared (``compare``)."""
