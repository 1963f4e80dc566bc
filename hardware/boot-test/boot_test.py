#!/usr/bin/env python3
"""Boot test: runs each flashable image from its bootloader's hand-off through our reset
handler in an emulated Cortex-M4 (unicorn), then takes one interrupt and checks that it lands
in our handler.

- module-nrf52840-uf2: the real Nordic nRF52 MBR at 0x0 (see `nordic_mbr`), our image at
  0x26000. The run starts at the MBR's reset vector. UICR.NRFFW[0] names a bootloader at
  0xF4000; a stand-in there does what the Adafruit bootloader's `bootloader_app_start` does
  when it hands over (forward address 0x26000 into the MBR's RAM word 0x2000_0000, MSP and
  PC from the app's vector table). Then RTC1 (embassy's time driver) is taken twice: once
  through whatever VTOR our reset handler left, once through the MBR's table (VTOR 0), the
  path an image that never sets VTOR depends on.
- flight-*-taulabs-bl: the Tau Labs bootloader's jump condition
  ((SP & 0x2FFE0000) == 0x20000000) and hand-off (MSP, PC; VTOR left on the bootloader's
  own table at 0x0800_0000), then TIM2 (embassy's time driver).
- flight-brushedsparky / flight-sparky2 (DFU): the ST ROM's `:leave` jump with VTOR still on
  a ROM-like table at 0x1FFF_0000, then TIM2.

Peripheral registers read as zero (memory stubs); the boot path, the stack, VTOR and the
exception entry are emulated as the Armv7-M architecture defines them. Usage:
    boot_test.py DIST_DIR [IMAGE_NAME ...]
Exit status 0 only if every image boots and every interrupt lands in our handler.
"""

import os
import struct
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

from unicorn import (UC_ARCH_ARM, UC_HOOK_CODE, UC_MODE_MCLASS, UC_MODE_THUMB, Uc,
                     UcError)
from unicorn.arm_const import UC_ARM_REG_LR, UC_ARM_REG_PC, UC_ARM_REG_SP, UC_CPU_ARM_CORTEX_M4

HERE = Path(__file__).resolve().parent
# Nordic's MBR is not ours to commit: it is read at test time from a SoftDevice hex that a
# registry package ships (Nordic's pc-ble-driver-py 0.11.4 sdist carries S132 3.1.0, whose
# first 0x1000 bytes are the nRF52 MBR, the same code family the Adafruit bootloader ships
# with S140). `MBR_SDIST` may point at an already downloaded copy.
MBR_PACKAGE = "pc-ble-driver-py==0.11.4"
MBR_MEMBER = "pc_ble_driver_py-0.11.4/pc_ble_driver_py/hex/sd_api_v3/s132_nrf52_3.1.0_softdevice.hex"
MBR_END = 0x1000  # the SoftDevice starts here
VTOR = 0xE000ED08
SCS = 0xE000E000
STEP_LIMIT = 2_000_000  # reset handler to main: bss/data loops, well under this

# Exception numbers (16 + IRQ): embassy's time drivers.
RTC1_EXC = 16 + 17  # nRF52840 RTC1
TIM2_EXC = 16 + 28  # STM32F405 TIM2


def elf_image(path):
    """(load segments [(addr, bytes)], symbols {name: addr}) of an ELF32 LE file."""
    e = path.read_bytes()
    if e[:6] != b"\x7fELF\x01\x01":
        raise ValueError(f"{path}: not an ELF32 LE file")
    phoff, shoff = struct.unpack_from("<II", e, 0x1C)
    phentsize, phnum, shentsize, shnum = struct.unpack_from("<HHHH", e, 0x2A)
    segments = []
    for i in range(phnum):
        kind, off, _vaddr, paddr, filesz = struct.unpack_from("<IIIII", e, phoff + i * phentsize)
        if kind == 1 and filesz:
            segments.append((paddr, e[off:off + filesz]))
    sections = [struct.unpack_from("<IIIIIIIIII", e, shoff + i * shentsize) for i in range(shnum)]
    symbols = {}
    for sh in sections:
        if sh[1] != 2:  # SHT_SYMTAB
            continue
        strtab = sections[sh[6]]
        for j in range(sh[5] // 16):
            name, value, _size, _info, _other, _shndx = struct.unpack_from(
                "<IIIBBH", e, sh[4] + j * 16)
            start = strtab[4] + name
            symbols[e[start:e.index(b"\0", start)].decode()] = value
    return segments, symbols


def ihex(path):
    """Bytes by address from an Intel HEX file, checksums checked."""
    mem, base = {}, 0
    for line in path.read_text().split():
        b = bytes.fromhex(line[1:])
        if sum(b) & 0xFF:
            raise ValueError(f"{path}: bad checksum in {line}")
        n, addr, kind = b[0], b[1] << 8 | b[2], b[3]
        if kind == 0:
            for i in range(n):
                mem[base + addr + i] = b[4 + i]
        elif kind == 4:
            base = (b[4] << 8 | b[5]) << 16
    return mem


class Machine:
    """A Cortex-M4 with flat memory regions and the bits of the SCS we need."""

    def __init__(self, regions):
        self.uc = Uc(UC_ARCH_ARM, UC_MODE_THUMB | UC_MODE_MCLASS)
        self.uc.ctl_set_cpu_model(UC_CPU_ARM_CORTEX_M4)
        for start, size in regions + [(SCS, 0x1000), (0x40000000, 0x100000),
                                       (0x50000000, 0x100000)]:
            self.uc.mem_map(start, size)
        self.trace = []

    def w32(self, addr, value):
        self.uc.mem_write(addr, struct.pack("<I", value))

    def r32(self, addr):
        return struct.unpack("<I", self.uc.mem_read(addr, 4))[0]

    def load(self, segments):
        for addr, data in segments:
            self.uc.mem_write(addr, bytes(data))

    def run_until(self, start, stop_at, limit):
        """Runs from `start` until PC reaches an address in `stop_at`; returns that address,
        or None if the limit is hit or the CPU faults."""
        reached = []

        def hook(uc, address, _size, _user):
            if address in stop_at:
                reached.append(address)
                uc.emu_stop()

        h = self.uc.hook_add(UC_HOOK_CODE, hook)
        try:
            self.uc.emu_start(start | 1, 0xFFFFFFFF, count=limit)
        except UcError as err:
            self.trace.append(f"CPU stopped at 0x{self.uc.reg_read(UC_ARM_REG_PC):08X}: {err}")
        finally:
            self.uc.hook_del(h)
        return reached[0] if reached else None

    def take_exception(self, exc, vtor, stop_at, limit=500):
        """Exception entry as the hardware does it (Armv7-M B1.5.6: push the basic frame,
        LR = EXC_RETURN, PC = vector[exc] from the table VTOR names), then runs until PC
        reaches an address in `stop_at`."""
        sp = (self.uc.reg_read(UC_ARM_REG_SP) - 32) & ~7
        pc = self.uc.reg_read(UC_ARM_REG_PC)
        for i, value in enumerate([0, 0, 0, 0, 0, 0xFFFFFFFF, pc, 0x01000000]):
            self.w32(sp + 4 * i, value)
        self.uc.reg_write(UC_ARM_REG_SP, sp)
        self.uc.reg_write(UC_ARM_REG_LR, 0xFFFFFFF9)
        vector = self.r32(vtor + 4 * exc)
        self.trace.append(f"exception {exc}: VTOR 0x{vtor:08X}, vector 0x{vector:08X}")
        if vector & 1 == 0:
            self.trace.append("vector is not a Thumb address: HardFault")
            return None
        return self.run_until(vector & ~1, stop_at, limit)


def boot_to_main(m, sp, reset, symbols):
    """From a bootloader's hand-off (MSP, PC) through our reset handler to `main`."""
    m.uc.reg_write(UC_ARM_REG_SP, sp)
    main = symbols["main"] & ~1
    if m.run_until(reset & ~1, {main}, STEP_LIMIT) != main:
        m.trace.append("never reached main")
        return False
    return True


def check_interrupt(m, exc, vtor, our_table, name, symbols):
    handler = m.r32(our_table + 4 * exc) & ~1
    expected = symbols.get(name)
    if expected is None or expected & ~1 != handler:
        m.trace.append(f"our vector {exc} is 0x{handler:08X}, not {name}")
        return False
    # Anything in the 0x0000_0000-0x0000_0FFF MBR or a ROM loop that does not reach the
    # handler within the step limit counts as "lost".
    landed = m.take_exception(exc, vtor, {handler})
    m.trace.append(f"  {'landed in' if landed == handler else 'did NOT reach'} {name} "
                   f"(0x{handler:08X})")
    return landed == handler


def stm32_machine(segments):
    m = Machine([(0x08000000, 0x100000), (0x1FFF0000, 0x10000), (0x10000000, 0x10000),
                 (0x20000000, 0x20000)])
    m.load(segments)
    return m


def rom_like_table(m, base):
    """A vector table whose every handler is `b .` (the ST ROM or another bootloader's
    table: an interrupt that goes there never comes back to us)."""
    loop = base + 0x400
    m.uc.mem_write(loop, b"\xfe\xe7")
    for i in range(1, 128):
        m.w32(base + 4 * i, loop | 1)


def boot_dfu(elf):
    """ST ROM bootloader, `dfu-util ... :leave`: jumps to the image at 0x0800_0000 with VTOR
    still on its own table in system memory."""
    segments, symbols = elf_image(elf)
    m = stm32_machine(segments)
    rom_like_table(m, 0x1FFF0000)
    m.w32(VTOR, 0x1FFF0000)
    table = 0x08000000
    ok = boot_to_main(m, m.r32(table), m.r32(table + 4), symbols)
    ok = ok and check_interrupt(m, TIM2_EXC, m.r32(VTOR), table, "TIM2", symbols)
    return ok, m.trace


def boot_taulabs(elf):
    """Tau Labs bootloader (flight/targets/bl/f4): jumps only if the initial SP passes its
    mask, sets MSP and PC from the firmware bank's table and leaves VTOR on its own."""
    segments, symbols = elf_image(elf)
    m = stm32_machine(segments)
    rom_like_table(m, 0x08000000)
    m.w32(VTOR, 0x08000000)
    table = 0x08020000
    sp = m.r32(table)
    if sp & 0x2FFE0000 != 0x20000000:
        m.trace.append(f"initial SP 0x{sp:08X} fails (SP & 0x2FFE0000) == 0x20000000: "
                       "the bootloader stays in DFU mode")
        return False, m.trace
    ok = boot_to_main(m, sp, m.r32(table + 4), symbols)
    ok = ok and check_interrupt(m, TIM2_EXC, m.r32(VTOR), table, "TIM2", symbols)
    return ok, m.trace


BOOTLOADER_STANDIN = 0xF4000


def nordic_mbr():
    """{address: byte} of Nordic's nRF52 MBR (below 0x1000), from the registry package."""
    sdist = os.environ.get("MBR_SDIST")
    if not sdist:
        cache = Path(tempfile.gettempdir()) / "taulink-mbr"
        found = sorted(cache.glob("pc_ble_driver_py-0.11.4.tar.gz"))
        if not found:
            subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                            "--no-binary", ":all:", "-d", str(cache),
                            MBR_PACKAGE], check=True)
            found = sorted(cache.glob("pc_ble_driver_py-0.11.4.tar.gz"))
        if not found:
            raise FileNotFoundError(f"pip did not fetch {MBR_PACKAGE}")
        sdist = found[0]
    with tarfile.open(sdist) as tar, tempfile.TemporaryDirectory() as tmp:
        member = tar.extractfile(MBR_MEMBER)
        if member is None:
            raise FileNotFoundError(f"{MBR_MEMBER} not in {sdist}")
        hexfile = Path(tmp) / "sd.hex"
        hexfile.write_bytes(member.read())
        image = ihex(hexfile)
    mbr = {a: b for a, b in image.items() if a < MBR_END}
    if len(mbr) < 0x100:
        raise ValueError("no MBR below 0x1000 in the SoftDevice hex")
    return mbr


def boot_uf2(elf):
    """Nordic MBR → (Adafruit bootloader stand-in) → our image at 0x26000."""
    segments, symbols = elf_image(elf)
    m = Machine([(0x0, 0x100000), (0x10000000, 0x2000), (0x20000000, 0x40000)])
    m.uc.mem_write(0x0, b"\xff" * 0x100000)
    m.uc.mem_write(0x10000000, b"\xff" * 0x2000)
    for addr, byte in nordic_mbr().items():
        m.uc.mem_write(addr, bytes([byte]))
    m.load(segments)
    # UICR.NRFFW[0]: bootloader start; NRFFW[1]: MBR parameter page (erased: no command).
    m.w32(0x10001014, BOOTLOADER_STANDIN)
    m.w32(0x10001018, 0xFE000)
    app = 0x26000
    code = BOOTLOADER_STANDIN + 0x100
    m.w32(BOOTLOADER_STANDIN, 0x20040000)
    m.w32(BOOTLOADER_STANDIN + 4, code | 1)
    # ldr r0,=app; ldr r1,=0x20000000; str r0,[r1]; ldr r1,[r0]; msr msp,r1;
    # ldr r0,[r0,#4]; bx r0
    m.uc.mem_write(code, struct.pack("<8H", 0x4804, 0x4905, 0x6008, 0x6801, 0xF381, 0x8808,
                                     0x6840, 0x4700))
    m.w32(code + 0x14, app)
    m.w32(code + 0x18, 0x20000000)
    # Power-on: VTOR 0, MSP and PC from the MBR's table.
    m.w32(VTOR, 0)
    m.uc.reg_write(UC_ARM_REG_SP, m.r32(0))
    main = symbols["main"] & ~1
    reset = m.r32(app + 4) & ~1
    if m.run_until(m.r32(4) & ~1, {reset}, 10_000) != reset:
        m.trace.append("the MBR never reached our reset handler")
        return False, m.trace
    m.trace.append(f"MBR → bootloader stand-in → our reset handler 0x{reset:08X}")
    if m.run_until(reset, {main}, STEP_LIMIT) != main:
        m.trace.append("never reached main")
        return False, m.trace
    forward = m.r32(0x20000000)
    m.trace.append(f"MBR forward word after our start-up: 0x{forward:08X}")
    ok = check_interrupt(m, RTC1_EXC, m.r32(VTOR), app, "RTC1", symbols)
    # The same interrupt through the MBR's own table, as if VTOR had not been set.
    ok = check_interrupt(m, RTC1_EXC, 0, app, "RTC1", symbols) and ok
    return ok, m.trace


def kind_of(name):
    if name.endswith("-uf2"):
        return boot_uf2
    if name.endswith("-taulabs-bl"):
        return boot_taulabs
    if name.startswith("flight-"):
        return boot_dfu
    return None


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    dist = Path(argv[1])
    names = argv[2:] or sorted(p.stem for p in dist.glob("*.elf") if kind_of(p.stem))
    failed = 0
    for name in names:
        test = kind_of(name)
        if test is None:
            print(f"{name}: no boot test for this image")
            continue
        ok, trace = test(dist / f"{name}.elf")
        print(f"{'PASS' if ok else 'FAIL'} {name} ({test.__name__})")
        for line in trace:
            print(f"    {line}")
        failed += not ok
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
