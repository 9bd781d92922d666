"""``touchbench demo``: the README's first command.

Shows the real ``haart`` dataset when ../shared/data is present, otherwise
the small ``haart-sample`` shipped with the package.
"""

from __future__ import annotations

import click

from ..datasets import load_dataset
from ..errors import DataError
from .data import format_info


@click.command()
def demo() -> None:
    """Run the main job on the embedded default."""
    try:
        ds = load_dataset("haart")
    except DataError as e:
        click.echo(f"(real HAART not available: {e}; using the built-in sample)", err=True)
        ds = load_dataset("haart-sample")
    click.echo(format_info(ds.info()))
