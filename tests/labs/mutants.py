"""Mutants of the reference solutions, one per common mistake: each is the solution with a
few lines changed, the tasks it must fail and a phrase the hint of each must contain.
``write_mutants`` writes them as files (the checker never sees where they came from)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mirrorlab.labs import LABS


@dataclass(frozen=True)
class Mutant:
    lab: str
    name: str
    edits: tuple[tuple[str, str], ...]
    fails: dict[str, str]
    """task id -> a phrase its hint must contain; every other task must pass."""

    def source(self) -> str:
        text = LABS[self.lab].solution.read_text()
        for old, new in self.edits:
            if old not in text:
                raise AssertionError(f"mutant {self.name}: {old!r} is not in the solution")
            text = text.replace(old, new)
        return text


QUAD = """    glTexCoord2f(0, 0)
    glVertex3f(-7, -3, -6)
    glTexCoord2f(0, 1)
    glVertex3f(-7, 5, -6)
    glTexCoord2f(1, 1)
    glVertex3f(-7, 5, 2)
    glTexCoord2f(1, 0)
    glVertex3f(-7, -3, 2)
"""
CORNERS = ((-7, -3, -6), (-7, 5, -6), (-7, 5, 2), (-7, -3, 2))


def quad(texcoords) -> str:
    """The mirror quad's lines with ``texcoords`` at the four corners."""
    return "".join(f"    glTexCoord2f{tuple(st)}\n    glVertex3f{corner}\n"
                   for st, corner in zip(texcoords, CORNERS, strict=True))


LAB20 = (
    Mutant("lab20", "wrong_extents", (("glOrtho(-6, 2, -3, 5, 0, 15)", "glOrtho(-4, 4, -4, 4, 0, 15)"),),
           {"capture_camera": "wrong extents", "capture_scene": "fix its projection"}),
    Mutant("lab20", "camera_wrong_side",
           (("gluLookAt(-7, 0, 0, 0, 0, 0, 0, 1, 0)", "gluLookAt(7, 0, 0, 0, 0, 0, 0, 1, 0)"),),
           {"capture_camera": "camera on the wrong side", "capture_scene": "fix its projection"}),
    Mutant("lab20", "texcoords_flipped", ((QUAD, quad(((1, 0), (1, 1), (0, 1), (0, 0)))),),
           {"mirror_quad": "flipped left-right"}),
    Mutant("lab20", "texcoords_upside_down", ((QUAD, quad(((0, 1), (0, 0), (1, 0), (1, 1)))),),
           {"mirror_quad": "upside down"}),
    Mutant("lab20", "texcoords_rotated", ((QUAD, quad(((0, 1), (1, 1), (1, 0), (0, 0)))),),
           {"mirror_quad": "rotated"}),
    Mutant("lab20", "mirror_in_capture",
           (("    lab.draw_scene(robot)\n    # TODO 3", "    lab.draw_scene(robot)\n    render_mirror()\n    # TODO 3"),),
           {"capture_scene": "drawn into its own capture"}),
    Mutant("lab20", "environment_not_bound",
           (("    glActiveTexture(GL_TEXTURE1)\n    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])\n    glCopyTexImage2D",
             "    glCopyTexImage2D"),),
           {"capture_copy": "overwrote METAL", "capture_scene": "went into METAL"}),
    Mutant("lab20", "environment_mipmaps",
           (("GL_TEXTURE_MIN_FILTER, GL_LINEAR)", "GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR)"),),
           {"environment_texture": "mipmaps", "mirror_texture": "black",
            "mirror_quad": "task 6"}),
    Mutant("lab20", "environment_repeat",
           (("GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE", "GL_TEXTURE_WRAP_S, GL_REPEAT"),),
           {"environment_texture": "repeat"}),
    Mutant("lab20", "base_not_textured", (('    robot["base"].texture = tex_ids[METAL]\n', ""),),
           {"base_texture": "base not textured", "capture_scene": "task 5"}),
    Mutant("lab20", "sampler_not_set", (("    glUniform1i(lab.texSampler, 1)\n", ""),),
           {"mirror_texture": "sampler uniform is not set", "mirror_quad": "task 6"}),
    Mutant("lab20", "passes_wrong_order",
           (("    create_mirror()\n", ""),
            ("    lab.draw_scene(robot)\n    # TODO 8: pass 2\n",
             "    lab.draw_scene(robot)\n    create_mirror()\n    # TODO 8: pass 2\n")),
           {"passes": "wrong order", "mirror_texture": "task 8", "mirror_quad": "task 8"}),
)

LEGACY = (
    # the lab text's own calls: GL_CLAMP works in the compatibility profile
    Mutant("lab20", "legacy_gl_clamp", (("GL_CLAMP_TO_EDGE", "GL_CLAMP"),), {}),
)

MUTANTS = (*LAB20,)


def write_mutants(folder: Path, mutants=MUTANTS) -> dict[str, Mutant]:
    """Write each mutant as ``folder/<lab>_<name>.py``; returns file stem -> mutant."""
    folder.mkdir(parents=True, exist_ok=True)
    written = {}
    for mutant in mutants:
        stem = f"{mutant.lab}_{mutant.name}"
        (folder / f"{stem}.py").write_text(mutant.source())
        written[stem] = mutant
    return written


def problems(expected_fails: dict[str, str], verdicts: dict[str, tuple[bool, str]]) -> list[str]:
    """What differs between a mutant's expected failures and the ``verdicts`` (task id ->
    (passed, hint)) the checker gave; empty when they agree."""
    found = []
    for task, (passed, hint) in verdicts.items():
        if task in expected_fails:
            if passed:
                found.append(f"{task} passed, expected to fail with {expected_fails[task]!r}")
            elif expected_fails[task] not in hint:
                found.append(f"{task} hint {hint!r} lacks {expected_fails[task]!r}")
        elif not passed:
            found.append(f"{task} failed unexpectedly: {hint}")
    return found
