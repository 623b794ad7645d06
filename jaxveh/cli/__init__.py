"""The ``jaxveh`` command line."""

from ._main import app as app, main as main
