"""The names of the ``state`` dimension of the results files, declared by the product that owns
them (acmm registers the 24 states of eq 4.47 when it is imported).  A module of its own, without
numpy, so that importing :mod:`acmm` stays light: the command line sets its BLAS thread defaults
(:mod:`acmm_qpp.cli`) before numpy is first imported.
"""
from __future__ import annotations

#: Provider of the names of the ``state`` dimension (a callable returning a sequence of names);
#: set by :func:`register_state_names` (acmm registers the 24 states of eq 4.47 on import).
_STATE_NAMES_PROVIDER = None


def register_state_names(provider) -> None:
    """Declare the entry names of the ``state`` dimension.

    Parameters
    ----------
    provider : callable
        Called without arguments when a layout is built; returns the state names (str).  A
        callable, so that the package declaring them is imported only when a file is written.
    """
    global _STATE_NAMES_PROVIDER
    _STATE_NAMES_PROVIDER = provider


def state_names() -> tuple:
    """The declared names of the ``state`` dimension.

    Returns
    -------
    tuple of str
        The names, or ``()`` when no product declared them.
    """
    return tuple(_STATE_NAMES_PROVIDER()) if _STATE_NAMES_PROVIDER is not None else ()
