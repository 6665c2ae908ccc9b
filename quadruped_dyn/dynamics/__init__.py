"""The paper's dynamics as CasADi graphs: leg kinematics, Newton-Euler, composite rigid bodies,
the GRF solve, the reduced model and its generated forms, and guarded numeric calls."""
