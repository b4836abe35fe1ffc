"""Alias of ``nlbeam.app.scenes`` (scene files: load, plan, run), kept for the names users
import."""
from nlbeam.app.scenes import (CACHE_DIR, Job, RunReport, Scene, SceneError, format_plan,
                               load_scene, plan, run_scene)

__all__ = ["SceneError", "Scene", "Job", "load_scene", "plan", "run_scene", "format_plan",
           "CACHE_DIR", "RunReport"]
