"""`make bench`: the bridge's costs and end-to-end figures next to the transport it sits on (not a test)."""
