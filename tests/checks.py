"""What the Python tests share: checks that are counted, printed when they
fail, and turned into the exit status at the end."""
import sys


class Checks:
    def __init__(self, name):
        self.name = name
        self.failures = []

    def __call__(self, ok, what):
        if not ok:
            self.failures.append(what)
            print("FAILED: " + what)

    def finish(self):
        """Prints the verdict and exits 1 when any check failed."""
        if self.failures:
            sys.exit("%s: %d check(s) failed" % (self.name, len(self.failures)))
        print("%s: all checks passed" % self.name)
