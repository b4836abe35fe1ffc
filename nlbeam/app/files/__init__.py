"""Files of the application floor.

``atomic`` and ``keys`` use the standard library only (``import nlbeam.app.files`` loads
nothing else): atomic writes, stale temporaries, content keys, the code fingerprint.
``frequency_response_hdf5`` and ``stochastic_hdf5`` write and read the analyses' results as
HDF5 (they import h5py; ``stamped_hdf5`` adds format and checksums); the results'
``save(path)`` and ``continuation.load`` / ``stochastic.load`` call them.
"""
from .atomic import (atomic_path, remove_stale_temporaries, write_bytes_atomic,
                     write_text_atomic)
from .keys import canonical_json, code_fingerprint, content_key, file_sha256

__all__ = ["atomic_path", "write_bytes_atomic", "write_text_atomic",
           "remove_stale_temporaries", "canonical_json", "content_key", "file_sha256",
           "code_fingerprint"]
