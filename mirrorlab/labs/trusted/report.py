"""The pages of a graded class.

``report.html``: the grades as a teacher looks at them, one row per student, each task's
result and hint (tasks named as the hints name them, ``task 1 (capture_camera)``), the
student | reference | difference picture as a thumbnail (a link to the full picture) and
the student's variant. A file that carries another student's numbers or the lab's own is
flagged beside its score, with whose and the score the policy for copies gives it; the
names not on the class list (not graded) and the class list's names with no submission
are listed above the table. Opens from disk with no server (pictures by relative path,
the sorting script inline). Clicking a column's header sorts by it;
``report.html#sort=COLUMN`` (or ``#sort=-COLUMN``, descending) opens it sorted. When the
page has loaded, ``<body>`` carries ``data-images-loaded`` and ``data-images-broken``: how
many thumbnails the browser drew and how many it could not.

``feedback/STUDENT.html`` (:func:`feedback_html`): one student's own page, to hand back:
their tasks, hints and picture (inline, so the file stands alone), and nothing of anyone
else's.
"""

from __future__ import annotations

import base64
from html import escape

from mirrorlab.labs import LabSpec

STYLE = """
body { font-family: sans-serif; margin: 1.5em; color: #222; }
table { border-collapse: collapse; }
th, td { border: 1px solid #ccc; padding: 4px 6px; vertical-align: top; font-size: 13px; }
th { background: #eee; cursor: pointer; user-select: none; white-space: nowrap; }
th.sorted-up::after { content: " \\25B2"; } th.sorted-down::after { content: " \\25BC"; }
td.pass { background: #e3f6e3; } td.fail { background: #fbe4e4; }
td.not-judged { background: #eee; color: #666; }
td.task { max-width: 14em; }
td.copied, .copy, td.not-graded { color: #a00; }
.id { font-size: 11px; display: block; color: #555; }
.copy { font-size: 11px; display: block; }
td.task .hint { color: #555; font-size: 11px; }
img.thumb { width: 270px; display: block; }
caption { text-align: left; padding-bottom: 0.6em; color: #444; }
"""

SCRIPT = """
function cellValue(row, column) {
  const cell = row.children[column];
  const value = cell.dataset.sort !== undefined ? cell.dataset.sort : cell.textContent;
  const number = parseFloat(value);
  return isNaN(number) ? value.toLowerCase() : number;
}
function sortBy(column, descending) {
  const table = document.getElementById('grades');
  const body = table.tBodies[0];
  const rows = Array.from(body.rows);
  rows.sort((a, b) => {
    const x = cellValue(a, column), y = cellValue(b, column);
    const order = x < y ? -1 : x > y ? 1 : 0;
    return descending ? -order : order;
  });
  rows.forEach(row => body.appendChild(row));
  table.querySelectorAll('th').forEach((th, i) => {
    th.classList.remove('sorted-up', 'sorted-down');
    if (i === column) th.classList.add(descending ? 'sorted-down' : 'sorted-up');
  });
  table.dataset.sortedBy = table.tHead.rows[0].children[column].dataset.key +
    (descending ? ' descending' : '');
}
document.querySelectorAll('#grades th').forEach((th, i) => {
  th.addEventListener('click', () => sortBy(i, th.classList.contains('sorted-up')));
});
const wanted = /sort=(-?)([A-Za-z0-9_]+)/.exec(location.hash);
if (wanted) {
  const headers = Array.from(document.querySelectorAll('#grades th'));
  const index = headers.findIndex(th => th.dataset.key === wanted[2]);
  if (index >= 0) sortBy(index, wanted[1] === '-');
}
window.addEventListener('load', () => {
  const images = Array.from(document.querySelectorAll('img.thumb'));
  const loaded = images.filter(img => img.complete && img.naturalWidth > 0).length;
  document.body.dataset.imagesLoaded = loaded;
  document.body.dataset.imagesBroken = images.length - loaded;
});
"""


def report_html(
    spec: LabSpec,
    grades: list,
    engine: str,
    seconds: float,
    copies: str = "flag",
    unlisted: list[str] | None = None,
    missing: list[str] | None = None,
) -> str:
    """The page for ``grades`` (:class:`mirrorlab.labs.grading.Grade`, in any order), copies
    scored by the policy ``copies``; ``unlisted``: submissions not on the class list (not
    graded), ``missing``: the class list's names with no submission."""
    from mirrorlab.labs.trusted.grading import safe_name

    tasks = spec.tasks
    head = [
        '<th data-key="student">student</th>',
        '<th data-key="score">score</th>',
        '<th data-key="picture">student | reference | difference</th>',
    ]
    head += [
        f'<th data-key="{t.id}" title="{escape(t.title)}">{escape(t.name)}</th>' for t in tasks
    ]
    head += ['<th data-key="variant">variant</th>', '<th data-key="seconds">seconds</th>']
    rows = []
    for grade in sorted(grades, key=lambda g: g.student):
        verdicts = {task_id: (passed, hint) for task_id, passed, hint in grade.tasks}
        picture = f"pictures/{safe_name(grade.student)}.png"
        copy = ""
        if grade.copied_from:
            booked = grade.booked(copies)
            scored = "no score (held)" if booked is None else f"scored {booked}"
            copy = (
                f'<span class="copy">copy: the numbers of {escape(grade.copy_of())}; '
                f"{scored} (--copies={escape(copies)})</span>"
            )
        ident = f'<span class="id">{escape(grade.student_id)}</span>' if grade.student_id else ""
        if grade.not_graded:
            score_cell = (
                f'<td class="score not-graded" data-sort="-1">not graded'
                f'<span class="copy">{escape(grade.not_graded)}</span></td>'
            )
        else:
            score_cell = (
                f'<td class="score" data-sort="{grade.score}">{grade.score}/{len(tasks)}{copy}</td>'
            )
        cells = [
            f'<td class="student">{escape(grade.student)}{ident}</td>',
            score_cell,
            f'<td class="picture" data-sort="{grade.score}"><a href="{escape(picture)}">'
            f'<img class="thumb" src="{escape(picture)}" alt="{escape(grade.student)}">'
            f"</a></td>",
        ]
        for task in tasks:
            if grade.not_graded:  # nothing was judged: no verdict to show
                cells.append('<td class="task not-judged" data-sort="-1">not graded</td>')
                continue
            passed, hint = verdicts.get(task.id, (False, "not checked"))
            word = "pass" if passed else "FAIL"
            note = f'<div class="hint">{escape(hint)}</div>' if hint else ""
            cells.append(
                f'<td class="task {"pass" if passed else "fail"}" '
                f'data-sort="{int(passed)}">{word}{note}</td>'
            )
        if grade.copied_from:
            cells.append(
                f'<td class="variant copied">{escape(grade.variant)}<br>numbers of '
                f"{escape(grade.copied_from)}</td>"
            )
        else:
            cells.append(f'<td class="variant">{escape(grade.variant)}</td>')
        cells.append(f'<td class="seconds">{grade.seconds:.2f}</td>')
        rows.append(f'<tr data-student="{escape(grade.student)}">{"".join(cells)}</tr>')
    full = sum(g.score == len(tasks) for g in grades)
    caption = (
        f"{len(grades)} submissions, {full} passing every task; graded in "
        f"{seconds:.1f} s on {escape(engine)}. Click a column's header to sort."
    )
    notes = []
    skipped = [g for g in grades if g.not_graded]
    if skipped:
        notes.append(
            '<p id="not-graded">Not graded, the checker\'s own failure (no score; grade '
            f"them again): {', '.join(f'<b>{escape(g.label)}</b>' for g in skipped)}</p>"
        )
    if unlisted:
        notes.append(
            '<p id="unlisted">Not graded, not on the class list: '
            f"{', '.join(f'<b>{escape(n)}</b>' for n in unlisted)}</p>"
        )
    if missing:
        notes.append(
            '<p id="missing">On the class list, no submission: '
            f"{', '.join(escape(n) for n in missing)}</p>"
        )
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{escape(spec.title)}: grades</title>
<style>{STYLE}</style>
</head>
<body>
<h1>{escape(spec.title)}: grades</h1>
{chr(10).join(notes)}
<table id="grades">
<caption>{caption}</caption>
<thead><tr>{"".join(head)}</tr></thead>
<tbody>
{chr(10).join(rows)}
</tbody>
</table>
<script>{SCRIPT}</script>
</body>
</html>
"""


FEEDBACK_STYLE = """
body { font-family: sans-serif; margin: 1.5em; color: #222; max-width: 70em; }
li { margin: 0.4em 0; } .pass { color: #176317; } .fail { color: #a01818; }
.hint { color: #444; font-size: 14px; } img { max-width: 100%; border: 1px solid #ccc; }
"""


def feedback_html(spec: LabSpec, grade) -> str:
    """One student's page: the lab, their score, each task's result and hint, and their
    picture (student | reference | difference) inline."""
    items = []
    titles = {t.id: t for t in spec.tasks}
    for task_id, passed, hint in grade.tasks:
        task = titles.get(task_id)
        title = f"{task.name}: {task.title}, in {task.function}()" if task else task_id
        word = "pass" if passed else "FAIL"
        note = f'<div class="hint">{escape(hint)}</div>' if hint else ""
        items.append(
            f'<li class="{"pass" if passed else "fail"}"><b>{word}</b> {escape(title)}{note}</li>'
        )
    image = base64.b64encode(grade.picture_png).decode()
    variant = "" if grade.variant == "default" else f" (variant {escape(grade.variant)})"
    if grade.not_graded:
        return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{escape(spec.title)}: {escape(grade.label)}</title>
<style>{FEEDBACK_STYLE}</style>
</head>
<body>
<h1>{escape(spec.title)}</h1>
<p>{escape(grade.label)}{variant}: Not graded. The checker failed on the grading machine
({escape(grade.not_graded)}); this says nothing of your file, which your teacher grades
again.</p>
</body>
</html>
"""
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{escape(spec.title)}: {escape(grade.label)}</title>
<style>{FEEDBACK_STYLE}</style>
</head>
<body>
<h1>{escape(spec.title)}</h1>
<p>{escape(grade.label)}{variant}: {grade.score} of {len(grade.tasks)} tasks passed.</p>
<ol>
{chr(10).join(items)}
</ol>
<p>Your frame (and capture) beside the reference solution's, and where they differ (red):</p>
<img alt="student | reference | difference" src="data:image/png;base64,{image}">
</body>
</html>
"""
