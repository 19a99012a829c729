#!/usr/bin/env python3
"""scikit-fmm's own test suite, run against envfield.fmm.

    python3 python/tests/skfmm_suite.py [--verbose]

Fetches scikit-fmm's source distribution from the Python registry (checked against the
registry's SHA-256; never committed: it is scikit-fmm's code), takes the doctests that
``skfmm.test()`` runs from its ``skfmm/__init__.py`` unchanged, and runs them with the name
``skfmm`` resolved to ``envfield.fmm`` and the module's globals (``distance``,
``travel_time``, ``extension_velocities``, ``heap``) taken from it. Exits non-zero when any
example fails. The download is kept in target/scikit-fmm/.
"""
import argparse
import ast
import doctest
import hashlib
import json
import os
import sys
import tarfile
import urllib.request

VERSION = "2025.6.23"
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CACHE = os.path.join(ROOT, "target", "scikit-fmm")


def fetch_sdist():
    os.makedirs(CACHE, exist_ok=True)
    with urllib.request.urlopen("https://pypi.org/pypi/scikit-fmm/json", timeout=60) as r:
        meta = json.load(r)
    sdist = next(u for u in meta["releases"][VERSION] if u["packagetype"] == "sdist")
    path = os.path.join(CACHE, sdist["filename"])
    if not os.path.exists(path):
        with urllib.request.urlopen(sdist["url"], timeout=120) as r:
            data = r.read()
        tmp = path + ".part"
        with open(tmp, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    digest = hashlib.sha256(open(path, "rb").read()).hexdigest()
    if digest != sdist["digests"]["sha256"]:
        os.remove(path)
        sys.exit("scikit-fmm's source distribution does not match the registry's SHA-256")
    return path


def testing_docstring(sdist):
    with tarfile.open(sdist) as tar:
        member = next(m for m in tar.getmembers() if m.name.endswith("skfmm/__init__.py"))
        source = tar.extractfile(member).read().decode("utf-8")
    tree = ast.parse(source)
    docs = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            doc = ast.get_docstring(node, clean=False)
            if doc and ">>>" in doc:
                docs[node.name] = doc
    return docs


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    import envfield.fmm

    sys.modules["skfmm"] = envfield.fmm
    globs = {name: getattr(envfield.fmm, name) for name in envfield.fmm.__all__}
    parser_ = doctest.DocTestParser()
    runner = doctest.DocTestRunner(verbose=args.verbose)
    total = failed = 0
    for name, doc in testing_docstring(fetch_sdist()).items():
        test = parser_.get_doctest(doc, dict(globs), "skfmm." + name, "skfmm/__init__.py", 0)
        result = runner.run(test)
        total += result.attempted
        failed += result.failed
    print("scikit-fmm %s's doctests against envfield.fmm: %d examples, %d failed"
          % (VERSION, total, failed))
    return 1 if failed or total == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
