"""Reliability tests: faulty links (hubwire.testing.faultlink), soak, hostile input, reconnects (docs/RELIABILITY.md)."""
