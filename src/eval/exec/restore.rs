//! M70–M73: the state is saved in the call's frame (control flow) and
//! brought back by lines written to the output; what those lines do to
//! the machine model is the machine's ([`Machine::restore_lines`],
//! [`Machine::restore_offsets`], [`Machine::restore_modes`]).
//!
//! [`Machine::restore_lines`]: crate::eval::state::Machine::restore_lines
//! [`Machine::restore_offsets`]: crate::eval::state::Machine::restore_offsets
//! [`Machine::restore_modes`]: crate::eval::state::Machine::restore_modes

use crate::diag::MachineError;
use std::rc::Rc;

use crate::diag::{Error, ErrorKind};
use crate::parse::ast::Span;
use crate::program::FileIndex;

use crate::eval::Interp;
use crate::eval::state::Env;
use crate::eval::state::restore::Saved;

impl Interp<'_> {
    /// M70 save, M71 invalidate, M72 restore, M73 save and restore on return.
    pub(in crate::eval) fn context_op(
        &mut self,
        op: u8,
        file: &Rc<FileIndex>,
        start: u32,
        span: Span,
    ) -> Result<(), Error> {
        match op {
            70 | 73 => {
                let m = self.mach.save(&self.params);
                let nested = self.flow.frames.len() > 1;
                let f = self.flow.frames.last_mut().expect("frame");
                f.saved_modal = Some(Box::new(m));
                f.auto_restore = op == 73 && nested;
            }
            71 => {
                let f = self.flow.frames.last_mut().expect("frame");
                f.saved_modal = None;
                f.auto_restore = false;
            }
            _ => {
                let saved = self
                    .flow
                    .frames
                    .last()
                    .and_then(|f| f.saved_modal.as_deref().cloned());
                match saved {
                    Some(m) => self.restore_modal(&m)?,
                    None => {
                        return Err(self.error_in_line(
                            ErrorKind::Machine(MachineError::NoSavedContext),
                            file,
                            start,
                            span,
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// Writes the words that bring the machine from the current state to
    /// `saved`, and adopts it, moving the position model as those words do.
    /// Writes nothing if nothing changed.
    pub(in crate::eval) fn restore_modal(&mut self, saved: &Saved) -> Result<(), Error> {
        let g92_now = self.params.g92_applied();
        let lines = self.mach.restore_lines(saved, g92_now, self.s.precision);
        for line in &lines.before {
            self.emit_raw(line.as_bytes())?;
        }
        let mut env = Env {
            s: self.s,
            params: &mut self.params,
            line: self.reader.line_idx + 1,
        };
        self.mach.restore_offsets(&mut env, saved, g92_now);
        for line in lines.coolant {
            self.emit_raw(line)?;
        }
        self.mach.restore_modes(saved);
        Ok(())
    }
}
