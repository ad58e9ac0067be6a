"""Scripted parametric models; each module has a ``build(**params)``.

Nothing is here yet; the models issue fills this package.
"""
