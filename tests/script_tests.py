"""The runner of the test scripts CTest starts directly (python3 tests/<folder>/test_*.py): every
function named test_* in the script, in order; each one's traceback on failure; a last line
'N passed, N failed'; exit 1 on any failure."""
import sys
import traceback


def run(namespace, before=None):
    """namespace: the script's globals(); before: called once first (a build, a server)."""
    if before:
        before()
    tests = [v for k, v in list(namespace.items()) if k.startswith("test_") and callable(v)]
    failed = 0
    for t in tests:
        try:
            t()
            print(f"ok   {t.__name__}", flush=True)
        except Exception:
            traceback.print_exc()
            print(f"FAIL {t.__name__}", flush=True)
            failed += 1
    print(f"{len(tests) - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)
