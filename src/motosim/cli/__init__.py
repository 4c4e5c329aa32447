"""The ``motosim`` command: the only layer that reads user files, prints and exits."""
