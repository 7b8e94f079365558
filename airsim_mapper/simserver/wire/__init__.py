"""The wire: Project AirSim's protocol as bytes and sockets, and the message shapes it carries.

`protocol` encodes and decodes frames and envelopes, `services` serves the services channel (Rep0),
`topics` the topics channel (Pair0, the topic table, subscriptions, last values) through the `outbox`,
and `messages` builds and parses the message and service-result dicts. Its face (`__all__`, the modules
the rooms above import): `messages`, `protocol`, `services`, `topics`.
"""

from __future__ import annotations

__all__ = ["messages", "protocol", "services", "topics"]
