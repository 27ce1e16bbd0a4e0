"""Study `tunnel`: long-train positioning with a leaky coaxial cable (seed 003; the model: docs/model/tunnel.md).

Modules: :mod:`geometry` (tunnel, LCX slot chain, cable), :mod:`materials` (Fresnel),
:mod:`rays` (image method and shooting-and-bouncing rays behind one interface),
:mod:`channel` (tabulated slot-to-receiver channel, RSSI map, delay spread, coverage),
:mod:`positioning` (RSSI ranging, TDOA, GDOP, CEP), :mod:`tracking` (KF, PF),
:mod:`simulate` (train runs), :mod:`figures`, :mod:`keys`.
"""
