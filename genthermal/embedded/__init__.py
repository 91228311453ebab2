"""The generated C on an embedded target: a Cortex-M4F emulated by QEMU.

* :mod:`~genthermal.embedded.toolchain` -- the cross toolchain (Debian ``gcc-arm-none-eabi``,
  newlib), bare-metal start-up, QEMU with semihosting, sizes, stack and instruction counts;
* :mod:`~genthermal.embedded.mission` -- a mission through the generated model, filter and
  prediction on the target, in double or single precision.

The C support files (start-up code, linker script, target programs) are package data in ``c/``.
"""
