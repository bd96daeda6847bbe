"""What each worker of a local cluster runs as it starts (Dask's ``preload``).

Ctrl-C in a terminal reaches every process of the foreground group: the sweep's, and its
local workers'. The sweep stops them itself, in order, after keeping what finished; a worker
that died of the same Ctrl-C first would only add its own traceback. So local workers ignore
SIGINT (the nanny still ends them when the cluster closes).
"""

from __future__ import annotations

import signal
import threading
from typing import Any


def dask_setup(worker: Any) -> None:
    """Dask's preload hook: ignore SIGINT in this worker process."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
