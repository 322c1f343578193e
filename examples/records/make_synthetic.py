"""Write the repository's synthetic earthquake record, src/srdda/data/records/synthetic.AT2.

The record (srdda.io.records.synthetic_record) is five fixed sines (0.7 to 5.2 Hz)
under a trapezoidal envelope (1 s rise, hold to 3 s, exponential decay), 6 s at
Δt = 0.01 s, peak 0.35 g, in the PEER NGA .AT2 layout. No random numbers: running
this script again gives the same file. The `newmark` verification case and the
example model quake-bolted-block.toml read it.

    python examples/records/make_synthetic.py
"""
from srdda.io.records import SYNTHETIC_RECORD, synthetic_record, write_at2

dt, values_g = synthetic_record()
write_at2(SYNTHETIC_RECORD, dt, values_g, "srdda synthetic record: 5 sines, trapezoidal envelope, PGA 0.35 g")
print(f"wrote {SYNTHETIC_RECORD} ({len(values_g)} points, dt = {dt} s)")
