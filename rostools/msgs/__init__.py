"""The type system: specs, the type store, generated codecs and formatters.

Import the submodules directly (``rostools.msgs.store``, ``rostools.msgs.codec``, ...); this
package module stays empty so that importing one of them stays cheap.
"""
