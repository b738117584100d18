"""Toy surrogate kinds enter a test the way a third-party package's would: through the plugin hook
``spflow_register_surrogate_kinds``, registered for the test and removed after it."""

import contextlib

import spflow


@contextlib.contextmanager
def surrogate_kinds_registered(*classes, name: str):
    """Register ``classes`` as surrogate kinds under the plugin name ``name`` for the ``with`` block."""

    class _Plugin:
        @spflow.hookimpl
        def spflow_register_surrogate_kinds(self, register):
            for cls in classes:
                register(cls)

    spflow.register_plugin(_Plugin(), name=name)
    try:
        yield
    finally:
        spflow.unregister_plugin(name)
