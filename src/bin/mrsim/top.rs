//! `mrsim top`: the dashboard on this terminal until `q`, Ctrl-C or the
//! end of the run ([`mrsim_top`] holds the model and the drawing).

use anyhow::{Context, Result, anyhow};
use mrsim_top::{Order, REFRESH, TableView, connect_observer, draw_with, wait_for_setup};
use mrsim_transport::Namespace;
use mrsim_transport::zenoh::ZenohOptions;
use std::io::IsTerminal;
use std::time::Duration;

/// Restores the terminal however `top` ends.
struct TerminalGuard;

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        ratatui::restore();
    }
}

/// `mrsim top`: attaches to run `run_id` (over Zenoh with `zenoh`) and
/// shows the dashboard until `q`, Ctrl-C, or the end of the run. Returns
/// the exit status.
pub fn run(run_id: &str, timeout: f64, zenoh: Option<ZenohOptions>) -> Result<i32> {
    let ns = Namespace::new(run_id).map_err(|e| crate::exit::invalid(e.to_string()))?;
    if !std::io::stdout().is_terminal() {
        return Err(crate::exit::invalid(
            "mrsim top draws on a terminal, and stdout is not one",
        ));
    }
    let timeout = Duration::from_secs_f64(timeout.max(0.0));
    let mut obs = connect_observer(&ns, "top", zenoh.as_ref(), timeout)?;
    let mut model =
        wait_for_setup(obs.as_mut(), timeout).with_context(|| format!("run `{run_id}`"))?;

    mrsim_sys::signal::catch_termination();
    let mut terminal = ratatui::try_init().context("cannot take over the terminal")?;
    let guard = TerminalGuard;
    let mut view = TableView::default();
    use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
    let end = loop {
        model.poll(obs.as_mut())?;
        terminal
            .draw(|f| draw_with(f, &model, &view))
            .context("cannot draw on the terminal")?;
        if model.finished() {
            break Ok(0);
        }
        if !obs.world_alive() {
            break Err(anyhow!(
                "the world of run `{run_id}` is gone without finishing the run (tick {})",
                model.tick()
            ));
        }
        if mrsim_sys::signal::received().is_some() {
            break Ok(0);
        }
        if event::poll(REFRESH).context("cannot read the keyboard")?
            && let Event::Key(k) = event::read().context("cannot read the keyboard")?
            && k.kind == KeyEventKind::Press
        {
            let quit = matches!(k.code, KeyCode::Char('q') | KeyCode::Esc)
                || (k.code == KeyCode::Char('c') && k.modifiers.contains(KeyModifiers::CONTROL));
            if quit {
                break Ok(0);
            }
            let n = model.scenario.robots.len();
            let page = terminal.size().map_or(20, |s| s.height.saturating_sub(10)) as isize;
            match k.code {
                KeyCode::PageDown | KeyCode::Char(' ') => view.scroll(page.max(1), n),
                KeyCode::PageUp => view.scroll(-page.max(1), n),
                KeyCode::Down | KeyCode::Char('j') => view.scroll(1, n),
                KeyCode::Up | KeyCode::Char('k') => view.scroll(-1, n),
                KeyCode::Home | KeyCode::Char('g') => view.offset = 0,
                KeyCode::End | KeyCode::Char('G') => view.scroll(n as isize, n),
                KeyCode::Char('s') => {
                    let worst = match view.order {
                        Order::Auto => n as isize > page,
                        Order::Scenario => false,
                        Order::Worst => true,
                    };
                    view.toggle_order(worst);
                }
                _ => {}
            }
        }
    };
    drop(guard);
    drop(terminal);
    if model.finished() {
        println!("{}", model.summary());
    }
    end
}
