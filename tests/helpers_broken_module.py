"""A plug-in module that fails when it is imported (the registry must say so, not crash)."""

raise RuntimeError("this module is broken on purpose")
