"""Input and output: the model file (TOML) and its schema, the results file (HDF5)."""
from .modelfile import ModelFileError, load_model, model_from_dict, model_to_dict, save_model
from .results_store import ResultsFileError, ResultsStore, StoredResult, read_results, resume

__all__ = ["ModelFileError", "load_model", "model_from_dict", "model_to_dict", "save_model",
           "ResultsFileError", "ResultsStore", "StoredResult", "read_results", "resume"]
