"""Study ``nr``: positioning a high-speed train from 5G NR SS bursts (source 000)."""

from railradio.nr.waveform.sequences import pss, sss

__all__ = ["pss", "sss"]
