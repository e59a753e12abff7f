"""Reliability tests: faulty links (tools/faultlink), soak, hostile input, reconnects (docs/RELIABILITY.md)."""
