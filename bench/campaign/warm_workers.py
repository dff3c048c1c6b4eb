"""One zygote per Dask worker: the campaign's cases start warm on any cluster.

:class:`ZygotePlugin` is a Dask worker plugin (``Client.register_plugin``): each worker of
the campaign's cluster (the local default or one started with Dask's own commands) starts
its :class:`bench.campaign.zygote.Zygote` when its first case asks for it
(:func:`worker_zygote`), starts it again if it died, and ends it when the plugin is
unregistered at the end of the campaign or the worker closes. The plugin's name carries
the campaign's token, so two campaigns on one scheduler keep their own zygotes.
"""

from __future__ import annotations

import threading
from typing import Any

from distributed import get_worker
from distributed.diagnostics.plugin import WorkerPlugin

from bench.campaign.zygote import Zygote
from dbc.errors import RunError

PLUGIN_PREFIX = "thruster-hil-zygote-"


class ZygotePlugin(WorkerPlugin):
    """A worker's zygote, started on first use (module docstring)."""

    def __init__(self, token: str) -> None:
        self.name = PLUGIN_PREFIX + token
        self._zygote: Zygote | None = None
        self._lock: threading.Lock | None = None

    def setup(self, worker: Any) -> None:
        """On the worker: nothing starts until a case asks."""
        self._lock = threading.Lock()

    def zygote(self) -> Zygote:
        """This worker's zygote, started now if it is not running."""
        assert self._lock is not None, "used on a worker only"
        with self._lock:
            if self._zygote is None or not self._zygote.alive():
                if self._zygote is not None:
                    self._zygote.close()
                self._zygote = Zygote()
            return self._zygote

    def teardown(self, worker: Any) -> None:
        """End the zygote (any run it still has is stopped with it)."""
        if self._zygote is not None:
            self._zygote.close()
            self._zygote = None


def worker_zygote(name: str) -> Zygote | None:
    """The zygote of plugin ``name`` on the Dask worker running this task; None outside a
    worker, where the plugin is not registered, or where the zygote cannot start (the case
    then starts cold: slower, the same result)."""
    try:
        plugin = get_worker().plugins.get(name)
    except ValueError:  # not in a worker
        return None
    if not isinstance(plugin, ZygotePlugin):
        return None
    try:
        return plugin.zygote()
    except RunError:
        return None
