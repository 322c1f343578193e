"""The paper's examples (Fan, Zheng & Zhao 2017, section 4) and their tables."""
from . import nunchaku, rockfall, sine_wave, swing
from .registry import EXAMPLES, Example, Row, examples_dir, get_example, register
from .runner import relative_error, run_example

__all__ = ["EXAMPLES", "Example", "Row", "examples_dir", "get_example", "register", "relative_error", "run_example",
           "swing", "nunchaku", "rockfall", "sine_wave"]
