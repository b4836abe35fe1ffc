"""Files of the application floor.

``atomic`` and ``keys`` use the standard library only (``import nlbeam.app.files`` loads
nothing else): atomic writes and content keys. ``frequency_response_hdf5`` and
``stochastic_hdf5`` write and read the analyses' results as HDF5 (they import h5py); the
results' ``save(path)`` and ``continuation.load`` / ``stochastic.load`` call them.
"""
from .atomic import atomic_path, write_text_atomic
from .keys import canonical_json, content_key

__all__ = ["atomic_path", "write_text_atomic", "canonical_json", "content_key"]
