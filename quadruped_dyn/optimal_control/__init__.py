"""Trajectory optimisation on the symbolic reduced model: a periodic gait cycle by CasADi + IPOPT (docs/optimal_control.md)."""
