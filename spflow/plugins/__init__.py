"""Built-in plugins. Each subpackage contributes stages (and the forward model its effects) through the same
``spflow_register_*`` hooks a third-party package uses; ``builtin.py`` is the one plugin module that wires them."""
