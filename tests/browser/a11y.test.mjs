// An accessibility pass (axe-core from npm, run inside the page): the viewer as a first user sees
// it, with the panel open and collapsed, the help and the data browser shown, at a laptop's size
// and at 800 px. No violation of serious or critical impact is allowed; the rest are printed.
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import { after, before, test } from 'node:test';
import { launch, openClient, startServer, waitFinal } from './harness.mjs';

const axeSource = fs.readFileSync(createRequire(import.meta.url).resolve('axe-core/axe.min.js'), 'utf8');
let server, browser;
before(async () => { server = await startServer(); browser = await launch(); });
after(async () => { await browser?.close(); await server?.stop(); });

async function audit(page, what) {
  await page.addScriptTag({ content: axeSource });
  const result = await page.evaluate(() => window.axe.run(document));
  console.log(`axe, ${what}: ${result.passes?.length ?? 0} rules passed, ${result.violations.length} violated`);
  const lines = result.violations.map((v) => `${v.impact} ${v.id}: ${v.help} (${v.nodes.map((n) => n.target.join(' ')).join(', ')})`);
  if (lines.length) console.log(`axe, ${what}:\n  ${lines.join('\n  ')}`);
  const serious = result.violations.filter((v) => v.impact === 'serious' || v.impact === 'critical');
  assert.deepEqual(serious.map((v) => `${v.id} at ${v.nodes.map((n) => n.target.join(' ')).join(', ')}`), [], what);
  return result.violations;
}

test('no serious accessibility violation in the viewer', async () => {
  const page = await openClient(browser, server.url, { width: 1280, height: 800 });
  await waitFinal(page);
  await audit(page, 'the first view');
  await page.click('#volume-browse');
  await page.waitForSelector('#files li button');
  await page.click('#help-button');
  await audit(page, 'help and data browser open');
  await page.close();
  const narrow = await openClient(browser, server.url, { width: 800, height: 600 });
  await waitFinal(narrow);
  await audit(narrow, 'at 800 x 600, panel collapsed');
  await narrow.close();
});

test('the audit finds what it is meant to find', async () => {
  // An unlabelled input and grey-on-grey text: the pass above can fail.
  const page = await openClient(browser, server.url);
  await waitFinal(page);
  await page.evaluate(() => {
    document.querySelector('#panel').append(Object.assign(document.createElement('input'), { id: 'unlabelled' }));
    const p = Object.assign(document.createElement('p'), { textContent: 'faint' });
    p.style.cssText = 'color:#777;background:#787878';
    document.querySelector('#panel').append(p);
  });
  await assert.rejects(audit(page, 'with planted faults'), /label|color-contrast/);
  await page.close();
});
