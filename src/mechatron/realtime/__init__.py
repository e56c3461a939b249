"""Real-time execution: the fixed-rate runner, the SIL/PIL bridge and HIL experiments
(docs/hil.md)."""
