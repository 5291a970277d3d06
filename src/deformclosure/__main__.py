"""``python -m deformclosure``: the same as the ``deformclosure`` command."""

from .cli.main import run

if __name__ == "__main__":  # pragma: no cover - exercised through a subprocess in the tests
    run()
