"""The compiled run loop of ``SimConfig(physics="compiled")`` (:mod:`.loop`) and CPython's float functions bit for
bit for its kernels (:mod:`.cpython_math`)."""
