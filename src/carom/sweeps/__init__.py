"""Parameter sweeps on Dask: ``carom sweep`` and :func:`carom.sweep`.

A sweep file (:mod:`carom.sweeps.spec`, ``docs/sweeps.md``) names a base scene, the keys to
vary, the seeds and the observables (:mod:`carom.sweeps.observe`); :func:`sweep`
(:mod:`carom.sweeps.runner`) runs every point as a Dask task and writes the table
(:mod:`carom.sweeps.table`) and the plots (:mod:`carom.sweeps.plots`). Dask is imported only
when a sweep runs (the ``sweep`` extra: ``pip install 'carom[sweep]'``).
"""

from carom.sweeps.runner import SweepInterrupted, SweepReport, sweep
from carom.sweeps.spec import SweepError, SweepSpec, builtin_sweeps, find_sweep, load_sweep

__all__ = [
    "SweepError",
    "SweepInterrupted",
    "SweepReport",
    "SweepSpec",
    "builtin_sweeps",
    "find_sweep",
    "load_sweep",
    "sweep",
]
