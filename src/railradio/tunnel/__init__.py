"""Study `tunnel`: long-train positioning with a leaky coaxial cable (source 003; the model: docs/model/tunnel.md).

Modules: :mod:`geometry` (tunnel, LCX slot chain, cable), :mod:`materials` (Fresnel),
:mod:`rays` (image method and shooting-and-bouncing rays behind one interface),
:mod:`lifting` (3-D rays from the ray families, polarization rules),
:mod:`channel` (tabulated slot-to-receiver channel, RSSI map, delay spread, coverage),
:mod:`measurement` (measurement model, shadowing and delay-error fields),
:mod:`separable` and :mod:`wideband` (the two receivers),
:mod:`positioning` (RSSI ranging, TDOA, GDOP, CEP), :mod:`tracking` (KF, PF),
:mod:`filters` (the trackers of one crossing), :mod:`simulate` (train runs),
:mod:`study` (config -> objects; order, tables, maps), :mod:`engine_checks` (engines
compared, far decay, cut-off), :mod:`sensitivity`, :mod:`peak_bias`, :mod:`figures`, :mod:`keys`.
"""
