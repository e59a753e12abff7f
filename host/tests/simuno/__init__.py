# A package, so that this folder's conftest.py is imported as `simuno.conftest` and does not replace
# the `conftest` module that host/tests/test_*.py import helpers from.
