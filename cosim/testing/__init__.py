"""Test doubles, oracles and test clients: for tests, benchmarks and examples, never for models.

Nothing in ``cosim`` outside this package imports it (a test walks the imports). Its modules use
only the public API of the models they stand beside.
"""
