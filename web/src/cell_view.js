// The robot cell's panel: its state and last picks (GET /api/cell), when the server knows the daemon.
import { getJSON, paths } from './api.js';
import { cell, fixed, row, vec } from './format.js';

export function startCellView(section, periodMs = 2000) {
  const update = async () => {
    let status;
    try {
      status = await getJSON(paths.cell());
    } catch (e) {
      section.hidden = true;
      return;
    }
    if (!status.configured) { section.hidden = true; return; }
    section.hidden = false;
    render(section, status);
  };
  update();
  return setInterval(update, periodMs);
}

function render(section, s) {
  section.replaceChildren();
  const h = document.createElement('h2');
  h.textContent = 'Robot cell ';
  const state = document.createElement('span');
  state.id = 'cell-state';
  state.className = `state-${s.state}`;
  state.textContent = s.state + (s.stop_reason ? `: ${s.stop_reason}` : '');
  h.appendChild(state);
  const p = document.createElement('p');
  p.textContent = s.reachable === false
    ? `status service ${s.address} unreachable: ${s.error || ''}`
    : `picks done ${s.picks_done}, failed ${s.picks_failed} · next slot ${s.next_slot + 1} of ${s.num_slots}` +
      ` · perception ${s.perception_connected ? 'connected' : 'lost'}, robot ${s.robot_connected ? 'connected' : 'lost'}` +
      (s.dry_run ? ' · dry run' : '');
  const table = document.createElement('table');
  table.id = 'pick-table';
  table.appendChild(row(['pick', 'outcome', 'source frame', 'score', 'box (m, base)', 'slot', 'program', 'detail']
    .map((t) => { const th = document.createElement('th'); th.textContent = t; return th; })));
  for (const pick of [...(s.picks || [])].reverse()) {
    table.appendChild(row([
      cell(`${pick.pick_id}`), cell(pick.outcome, `outcome-${pick.outcome}`),
      cell(`${pick.source}#${pick.frame_id}`), cell(fixed(pick.score, 2)), cell(vec(pick.box_position)),
      cell(`${pick.slot}`), cell(`${fixed(pick.program_s, 1)} s`), cell(pick.detail || ''),
    ]));
  }
  section.append(h, p, table);
}
