"""Scenes: a TOML file that names a model, the periodic and stochastic analyses, and the
figures and tables wanted; ``run_scene`` computes only what those outputs need, caches each
analysis in HDF5 under a key made of exactly its inputs, and reuses it.

- ``schema``: the file format (sections, keys, defaults), ``load_scene`` -> ``Scene``;
- ``plan``: the analyses the outputs need, keyed and marked cached (``plan``, ``format_plan``);
- ``run``: ``run_scene`` (compute what is missing, cache it, write the outputs);
- ``outputs``: the CSV tables and the dispatch of the figures (drawn in ``nlbeam.app.plots``).
"""
from .plan import CACHE_DIR, Job, format_plan, plan
from .run import RunReport, run_scene
from .schema import Scene, SceneError, load_scene

__all__ = ["SceneError", "Scene", "Job", "load_scene", "plan", "run_scene", "format_plan",
           "CACHE_DIR", "RunReport"]
