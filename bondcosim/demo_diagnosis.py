"""The demo's last step: one diagnosis of a recording with a concealed effect, and its report."""
from __future__ import annotations

import time
from pathlib import Path

__all__ = ["run_diagnosis"]

#: The demo's case (``diagnosis.cases``): the PAM joint whose seesaw friction grows with the
#: chamber pressures, a physics the nominal Kikuuwe friction of seed 000 leaves out.
DEMO_CASE = "pam_pressure_friction"
#: The shortened demo's case (for tests): Coulomb friction hidden from a mass-spring-damper.
QUICK_CASE = "msd_coulomb"


def run_diagnosis(out: Path, *, quick: bool = False) -> dict:
    """Generate the case's recording into `out`, diagnose it, save the report; returns the files."""
    from diagnosis.cases import case
    from diagnosis.cases.generate import manifest_entry, write_case
    from diagnosis.diagnose import diagnose

    chosen = case(QUICK_CASE if quick else DEMO_CASE)
    csv, rec = write_case(chosen, out)
    entry = manifest_entry(chosen, rec)
    print(f"   recording {csv} ({entry['description']}); the concealed effect is not told to the tool")
    command = (f"bondcosim diagnose {entry['model']} {csv.name} "
               + " ".join(f"--input {b}" for b in entry["inputs"]) + " "
               + " ".join(f"--output {b}" for b in entry["outputs"]))
    print(f"   same as: {command}")
    start = time.perf_counter()
    report = diagnose(entry["model"], csv, inputs=entry["inputs"], outputs=entry["outputs"],
                      time=entry["time"], progress=True)
    saved = report.save(out / "diagnosis")
    print("   " + report.text.replace("\n", "\n   "))
    print(f"   diagnosed in {time.perf_counter() - start:.1f} s; concealed: {entry['kind']} at "
          f"{entry['place']['kind']} {entry['place']['name']}")
    written = {"diagnosis:recording": csv}
    written.update({f"diagnosis:{role}": Path(path) for role, path in saved.items()})
    return written
