"""Study ``chain``: one railway, one chain (docs/model/chain.md).

The ``nr`` study's tracked position error replaces the assumed GNSS/INS error of the
``handover`` study's position input; a Gauss–Markov sweep of the position error σ tells how
accurate positioning must be for the joint decision to beat A3.
"""
