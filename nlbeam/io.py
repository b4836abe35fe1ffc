"""Alias of ``nlbeam.app.files`` (atomic writes, content keys), kept for the name users
import; standard library only."""
from nlbeam.app.files import atomic_path, canonical_json, content_key, write_text_atomic

__all__ = ["atomic_path", "write_text_atomic", "canonical_json", "content_key"]
