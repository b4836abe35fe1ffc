"""The application floor: what people and files meet. Imports run downward only: this floor
uses ``continuation``, ``stochastic`` and the nlbeam core; nothing below imports it (except
the documented aliases and the results' save/load, listed in tests/test_floors.py). It is
the only place that imports matplotlib, h5py and dask.

- ``cli``: the ``nlbeam`` command; ``demo``: the scene ``nlbeam demo`` runs;
- ``defaults``: the defaults of the scene files and the command line, in one place (the
  analyses' own, read from their signatures, and the paper's study);
- ``scenes/``: scene files (schema, plan, run, outputs);
- ``compare``: PSD peaks mapped onto the periodic diagram;
- ``sweeps``: independent jobs here, on a process pool or on Dask;
- ``files/``: atomic writes, content keys, the HDF5 files of the results;
- ``plots/``: every figure.

Importing this package loads nothing but this docstring; each module imports what it uses.
"""
