"""The run engine: plans a protocol into tasks, runs them (in parallel), writes reports."""

from .runner import (
    Plan,
    RunResult,
    default_results_dir,
    plan_run,
    run_plan,
    run_protocol,
)

__all__ = ["Plan", "RunResult", "default_results_dir", "plan_run", "run_plan", "run_protocol"]
