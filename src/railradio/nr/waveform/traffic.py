"""Which RRH serves the train: the network's decision, part of the synthesis.

Each RRH is its own cell (the source gives every RRH its own PCI), so only the serving cell
carries the train's data (:class:`railradio.nr.synthesis.synthesizer.Synthesizer`, ``data_beam``). The
network picks it from the true large-scale received power (path loss, shadowing, the best
SS beam; no fast fading) with a hysteresis: a neighbour takes over when it is stronger than
the serving cell by ``hysteresis_db`` (the A3 entering condition of TS 36.331 §5.5.4.4 with
a3-Offset 0, the handover study's default hysteresis). The receiver never sees this
decision.

The state restarts at fixed epochs (every ``reset_every``: the strongest cell serves), so
the serving cell of an epoch depends only on the epochs since the last restart and a shard
gives the same bursts whatever the shard count (the shard replays those epochs first). A
restart changes the serving cell only where the hysteresis kept a weaker one; the share of
such epochs is measured in tests/nr/test_traffic.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass(frozen=True)
class ServingRule:
    """The network's serving-cell rule: hysteresis [dB] and restart period [epochs]."""

    hysteresis_db: float = 3.0
    reset_every: int = 100

    def __post_init__(self) -> None:
        if not self.hysteresis_db >= 0:
            raise ValueError(f"hysteresis_db must be >= 0, got {self.hysteresis_db!r}")
        if isinstance(self.reset_every, bool) or int(self.reset_every) != self.reset_every or self.reset_every < 1:
            raise ValueError(f"reset_every must be an integer >= 1, got {self.reset_every!r}")


class ServingCell:
    """The network's serving-cell state over consecutive epochs."""

    def __init__(self, rule: ServingRule):
        self.rule = rule
        self.serving = -1

    def reset(self) -> None:
        """Forget the serving cell (-1: none); the next :meth:`update` picks the strongest RRH."""
        self.serving = -1

    def update(self, epoch: int, rrh: NDArray[np.int64], power_dbm: NDArray[np.float64]) -> int:
        """The serving RRH at ``epoch`` given the RRHs in range and their large-scale power
        [dBm]; -1 when no RRH is in range.

        Parameters
        ----------
        epoch : int
            Epoch index; at multiples of ``rule.reset_every`` the strongest RRH serves.
        rrh : numpy.ndarray of int64
            Indices of the RRHs in range: [R].
        power_dbm : numpy.ndarray
            Their large-scale received power [dBm]: [R].

        Returns
        -------
        int
            The serving RRH index, or -1.
        """
        rrh = np.asarray(rrh)
        if rrh.size == 0:
            self.serving = -1
            return -1
        best = int(np.argmax(power_dbm))
        at = np.flatnonzero(rrh == self.serving)
        if int(epoch) % self.rule.reset_every == 0 or at.size == 0:
            self.serving = int(rrh[best])
        elif power_dbm[best] > power_dbm[at[0]] + self.rule.hysteresis_db:
            self.serving = int(rrh[best])
        return self.serving
