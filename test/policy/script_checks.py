"""Pass/fail bookkeeping shared by test/policy's unit tests of the Python scripts.

  from script_checks import Checks
  check = Checks()
  check(value == expected, "what the claim is")   # prints "ok   ..." or "FAIL ..."
  sys.exit(check.exit_code())                     # prints the summary; 1 if any claim failed

A test keeps going after a failed claim, so one run lists every claim that fails.
"""


class Checks:
    """Callable: check(ok, what) records one claim. failures lists the claims that failed, in order."""

    def __init__(self):
        self.failures = []

    def __call__(self, ok, what):
        print(f"{'ok  ' if ok else 'FAIL'} {what}")
        if not ok:
            self.failures.append(what)

    def exit_code(self):
        """Prints the summary line and returns the process's exit status (0: every claim held)."""
        print(f"FAILED: {len(self.failures)} of the claims: " + "; ".join(self.failures) if self.failures
              else "all passed")
        return 1 if self.failures else 0
