"""Where the custom-force hook comes from. In the package ``nlbeam._kernels`` there is none. An
uncached copy of the package made by ``nlbeam.custom`` sets ``_USER_FORCE_OVERRIDE`` on its
package module before importing it; a copy cached on disk replaces this file by one that
imports the force by its module and qualified name (and sets CACHE = True)."""
import sys

USER_FORCE = getattr(sys.modules[__name__.rpartition(".")[0]], "_USER_FORCE_OVERRIDE", None)
CACHE = USER_FORCE is None
