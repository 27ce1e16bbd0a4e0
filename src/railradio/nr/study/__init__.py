"""The nr study's experiments as the workflow runs them: the runs and their sensitivity cases,
the reproduction map, the fidelity target, the published records, the key numbers and the
figures. Unlike the layers below it, this package re-exports nothing: each workflow script
imports the one experiment module it runs, so that its code fingerprint
(:func:`railradio.codedeps.script_code_hash`, which counts a package's ``__init__``) holds that
module's closure and not every experiment's.
"""
