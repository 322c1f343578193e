"""``python -m srdda``: the command line ``srdda``, where its console script is not installed (a source tree)."""
from .apps.cli import main

if __name__ == "__main__":
    main(prog_name="srdda")
