"""The run engine: prepares an evaluation, plans it into tasks, runs them (in parallel), stores the results."""

from .planning import Plan, plan_run
from .runner import RunResult, default_results_dir, run_plan, run_protocol

__all__ = ["Plan", "RunResult", "default_results_dir", "plan_run", "run_plan", "run_protocol"]
