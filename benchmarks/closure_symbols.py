"""Why the two integration loops need names of their own: numba's disk cache mixes up two
closures of one name compiled in two processes (seconds, no nlbeam kernel compiled).

python benchmarks/closure_symbols.py

A module with two closures of one factory (``inner``, k = 2 and k = 3; bodies large enough
that LLVM keeps them as calls) and a cached caller of each (``top_a``, ``top_b``). Process B
compiles ``top_b`` into a numba cache folder of its own; process A compiles ``top_a`` in
another folder, copies ``top_b``'s cache entry into it (as ``nlbeam.app.warmup.adopt_cached``
does) and calls both. numba names compiled code by module, qualified name, argument types and
a count of the compiles in its process, so both processes name their ``inner`` alike, and in
A the loaded ``top_b`` calls A's ``inner`` (k = 2): it returns what ``top_a`` returns. With the
closures renamed before their first compile (as ``nlbeam._kernels.loop._loop_for`` does) the
loaded ``top_b`` returns what it returned in B. Prints both cases.
"""
import json
import os
import subprocess
import sys
import tempfile

_BODY = "\n".join(f"        if x > {i}.5:\n            s += k * x * {i + 1}.0 / (x + {i}.25)\n"
                  f"        else:\n            s -= k / (x + {i}.75)" for i in range(200))

MODULE = f'''
import os
from numba import njit

def _make(k):
    def inner(x):
        s = 0.0
{_BODY}
        return s
    if os.environ.get("RENAME") == "1":
        inner.__qualname__ = inner.__name__ = "inner_%d" % int(k)
    return njit(cache=True)(inner)

inner_a = _make(2.0)
inner_b = _make(3.0)

@njit(cache=True)
def top_a(x):
    return inner_a(x)

@njit(cache=True)
def top_b(x):
    return inner_b(x)
'''

RUN = '''
import json, sys
import closures
if sys.argv[1] == "b":
    print(json.dumps([closures.top_b(1.0), closures.top_b._cache._cache_path]))
else:
    from numba.core.caching import IndexDataCacheFile
    a = closures.top_a(1.0)
    mine = closures.top_b._cache._cache_file
    theirs = IndexDataCacheFile(sys.argv[2], mine._index_name[:-len(".nbi")],
                                mine._source_stamp)
    for key, name in theirs._load_index().items():
        mine.save(key, theirs._load_data(name))
    b = closures.top_b(1.0)
    print(json.dumps([a, b, sum(closures.top_b.stats.cache_hits.values())]))
'''


def _run(folder, cache, rename, *args):
    env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(folder, cache), RENAME=rename,
               PYTHONPATH=folder)
    out = subprocess.run([sys.executable, "-c", RUN, *args], env=env, capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def main():
    for rename in ("0", "1"):
        with tempfile.TemporaryDirectory(prefix="nlbeam-closures-") as folder:
            with open(os.path.join(folder, "closures.py"), "w") as f:
                f.write(MODULE)
            in_b, path = _run(folder, "B", rename, "b")
            a, b, hits = _run(folder, "A", rename, "adopt", path)
            print(f"closures {'renamed' if rename == '1' else 'of one name'}: top_b in its own "
                  f"process {in_b:.6f}; loaded beside top_a ({a:.6f}): {b:.6f} "
                  f"({'a cache hit' if hits else 'compiled'}) -> "
                  f"{'right' if b == in_b else 'WRONG: it ran the other closure'}")


if __name__ == "__main__":
    main()
