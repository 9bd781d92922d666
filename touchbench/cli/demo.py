"""``touchbench demo``: the README's first command.

Runs the shipped protocol ``demo-haart`` (the challenge split on the real HAART
recordings) when the HAART data is found (``core.paths``), otherwise ``tiny``
(the built-in synthetic ``tiny`` scene, no data needed), saying so before the
run (with where it looked) and after the leaderboard, then prints the
leaderboard of the run: its numbers once (the run's own summary is left out).
"""

from __future__ import annotations

import click

from ..core.errors import DataError
from .common import example, jobs_option


@click.command(epilog=example("touchbench demo --jobs 2"))
@jobs_option
@click.pass_context
def demo(ctx: click.Context, jobs: int) -> None:
    """Run the main job on the embedded default and show its leaderboard."""
    from ..core.paths import raw_folder
    from ..engine.runner import default_results_dir
    from ..protocols.library import find_protocol
    from ..protocols.loading import load_protocol
    from .reports import leaderboard
    from .run import run

    try:
        raw_folder("haart", None, "HAART")
        name, missing = "demo-haart", None
    except DataError as e:
        name, missing = "tiny", str(e)
        click.echo(f"real HAART data not found: running the built-in tiny scene (synthetic data) instead. {missing}",
                   err=True)
    ctx.invoke(run, protocol=name, jobs=jobs, summary=False)  # the leaderboard below gives the numbers once
    out = default_results_dir(load_protocol(find_protocol(name)))
    ctx.invoke(leaderboard, results=(str(out),))
    if missing is not None:
        click.echo("\nThese results are of the synthetic scene 'tiny', not of real data: the HAART data was not "
                   "found. Set TOUCHBENCH_DATA_DIR to the folder that holds haart/ to run the real demo.", err=True)
