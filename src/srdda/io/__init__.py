"""Input and output: the model file (TOML) and its schema."""
from .modelfile import ModelFileError, load_model, model_from_dict, model_to_dict, save_model

__all__ = ["ModelFileError", "load_model", "model_from_dict", "model_to_dict", "save_model"]
