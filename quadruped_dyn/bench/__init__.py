"""Benchmarks: the generated C against Pinocchio and other libraries' generated code, same run."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "harnesses": ("HARNESSES", "PINOCCHIO_CXX_FLAGS", "cmeel_prefix", "require_headers", "pinocchio_program"),
    "cppadcg": ("PEER", "PeerTiming"),
    "timing_counts": ("MAX_CALLS", "MAX_REPS", "check_counts"),
    "placement": ("TimedProgram", "parse_timings", "median_over_rounds"),
    "peers": ("PEERS", "ADAM_PAIRS", "PeerEntry", "parse_peers", "adam_functions", "check_adam", "run_peers", "peers_table"),
    "call_cost": ("CODE_BUDGET_BYTES", "CallCost", "arithmetic_operations", "cpu_model", "robot_call_costs",
                  "generated_call_costs"),
    "timing": ("FD_R_TARGET", "PAIRS", "BenchEntry", "BenchReport", "pinocchio_harness", "run_bench"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
