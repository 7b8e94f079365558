"""The converter catalogue's entries, one module a family; `airsim_mapper.convert.catalog` assembles them.

`model` says what an entry holds and how the engine runs a converter; the other modules list the entries
of one family each, in catalogue order.
"""
