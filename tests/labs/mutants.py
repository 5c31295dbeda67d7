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
    Mutant("lab20", "wrong_extents",
           (("glOrtho(-6, 2, -3, 5, 0, 15)", "glOrtho(-4, 4, -4, 4, 0, 15)"),),
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
           (("    lab.draw_scene(robot)\n    # TODO 3",
             "    lab.draw_scene(robot)\n    render_mirror()\n    # TODO 3"),),
           {"capture_scene": "drawn into its own capture"}),
    Mutant("lab20", "environment_not_bound",
           (("    glActiveTexture(GL_TEXTURE1)\n"
             "    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])\n    glCopyTexImage2D",
             "    glCopyTexImage2D"),),
           {"capture_copy": "overwrote METAL", "capture_scene": "went into METAL"}),
    Mutant("lab20", "environment_mipmaps",
           (("GL_TEXTURE_MIN_FILTER, GL_LINEAR)",
             "GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR)"),),
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

SPHEREMAP = (
    Mutant("spheremap", "reflect_sign",
           (("return u - 2.0 * dot(n, u) * n;", "return 2.0 * dot(n, u) * n - u;"),),
           {"reflection": "wrong way", "side_by_side": "tasks 1 and 2"}),
    Mutant("spheremap", "reflect_no_two",
           (("return u - 2.0 * dot(n, u) * n;", "return u - dot(n, u) * n;"),),
           {"reflection": "factor 2", "side_by_side": "tasks 1 and 2"}),
    Mutant("spheremap", "st_no_plus_one",
           (("(r.z + 1.0) * (r.z + 1.0)", "r.z * r.z"),),
           {"sphere_coordinates": "r.z + 1", "side_by_side": "tasks 1 and 2"}),
    Mutant("spheremap", "st_swapped",
           (("vec2(r.x / m + 0.5, r.y / m + 0.5)", "vec2(r.y / m + 0.5, r.x / m + 0.5)"),),
           {"sphere_coordinates": "swapped", "side_by_side": "tasks 1 and 2"}),
    Mutant("spheremap", "texgen_object_linear",
           (("glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
             "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_OBJECT_LINEAR)"),),
           {"texgen_setup": "GL_OBJECT_LINEAR", "side_by_side": "tasks 3 and 4"}),
    Mutant("spheremap", "texgen_left_on",
           (("    glDisable(GL_TEXTURE_GEN_S)\n    glDisable(GL_TEXTURE_GEN_T)\n", ""),),
           {"texgen_draw": "left on"}),
    Mutant("spheremap", "texgen_only_s", (("    glEnable(GL_TEXTURE_GEN_T)\n", ""),),
           {"texgen_draw": "for t is off", "side_by_side": "tasks 3 and 4"}),
)

CUBEMAP = (
    Mutant("cubemap", "face_signed_max", (("    vec3 a = abs(r);", "    vec3 a = r;"),),
           {"face_selection": "largest signed", "live_frame": "tasks 1 to 4"}),
    Mutant("cubemap", "st_swapped",
           (("return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
             "return vec2((tc / ma + 1.0) / 2.0, (sc / ma + 1.0) / 2.0);"),),
           {"face_coordinates": "swapped", "live_frame": "tasks 1 to 4"}),
    Mutant("cubemap", "st_not_divided",
           (("return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
             "return vec2((sc + 1.0) / 2.0, (tc + 1.0) / 2.0);"),),
           {"face_coordinates": "divided by |major axis|", "live_frame": "tasks 1 to 4"}),
    Mutant("cubemap", "up_wrong",
           (("((1, 0, 0), (0, -1, 0))", "((1, 0, 0), (0, 1, 0))"),
            ("((-1, 0, 0), (0, -1, 0))", "((-1, 0, 0), (0, 1, 0))"),
            ("((0, 0, 1), (0, -1, 0))", "((0, 0, 1), (0, 1, 0))"),
            ("((0, 0, -1), (0, -1, 0))", "((0, 0, -1), (0, 1, 0))")),
           {"capture_cameras": "up must be", "capture_copy": "task 3",
            "live_frame": "tasks 1 to 4"}),
    Mutant("cubemap", "fov_60", (("gluPerspective(90, 1, 0.05, 50)",
                                  "gluPerspective(60, 1, 0.05, 50)"),),
           {"capture_cameras": "field of view 60", "capture_copy": "task 3",
            "live_frame": "tasks 1 to 4"}),
    Mutant("cubemap", "faces_swapped_y",
           (("((0, 1, 0), (0, 0, 1)),      # POSITIVE_Y", "((0, -1, 0), (0, 0, -1)),   # Y-"),
            ("((0, -1, 0), (0, 0, -1)),    # NEGATIVE_Y", "((0, 1, 0), (0, 0, 1)),     # Y+")),
           {"capture_cameras": "wrong order", "capture_copy": "task 3",
            "live_frame": "tasks 1 to 4"}),
    Mutant("cubemap", "capture_after_camera",
           (("    capture_cube()\n    glClear", "    glClear"),
            ("    lab.draw_scene()\n    lab.draw_sphere",
             "    lab.draw_scene()\n    capture_cube()\n    lab.draw_sphere")),
           {"live_frame": "wrong order"}),
)

MUTANTS = (*LAB20, *SPHEREMAP, *CUBEMAP)


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
