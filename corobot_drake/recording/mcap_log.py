"""The run's topics written to an MCAP file (`--mcap FILE.mcap`), which Foxglove opens as it is.

    log = McapLog("run.mcap")
    sim = Simulation(scenario, foxglove=log.context)
    sim.advance(10.0)
    log.close()               # finishes the file (its summary and index)

The publishers (`publishers.py`) log on `log.context`; the MCAP writer is that context's
sink (foxglove-sdk's `open_mcap`, zstd chunks). A live server (`foxglove_live.py`) can share
the context: the same messages go to both.
"""

from pathlib import Path

import foxglove


class McapLog:
    """An MCAP file being written from a foxglove Context (a new one unless given)."""

    def __init__(self, path: str | Path, context: foxglove.Context | None = None):
        self.path = Path(path)
        self.context = context or foxglove.Context()
        self._writer = foxglove.open_mcap(self.path, allow_overwrite=True, context=self.context)

    def close(self) -> None:
        """Finishes the file. Idempotent. OSError when it cannot be written (a full disk:
        foxglove-sdk's writer reports it only here, as a RuntimeError)."""
        if self._writer is not None:
            writer, self._writer = self._writer, None
            try:
                writer.close()
            except RuntimeError as e:
                raise OSError(str(e).splitlines()[0]) from None

    def __enter__(self) -> "McapLog":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
