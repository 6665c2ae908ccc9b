"""Benchmarks: the generated C against Pinocchio and other libraries' generated code, same run."""
