//! Standard output that fails cleanly. The crate's `print!` and `println!` (defined here, they
//! shadow std's throughout the crate) write to stdout and, when the write fails, end the process
//! with a message instead of std's panic: a closed pipe (`htngtp plan ... | head -c1`) ends it
//! quietly with the shell's code for SIGPIPE (141), any other error (a full disk, `> /dev/full`)
//! with `error: cannot write the output: ...` and exit 3. `eprint!`/`eprintln!` ignore their
//! write errors: there is nowhere left to report them.

use std::io::{ErrorKind, Write};

/// The exit status of a process whose output pipe was closed (128 + SIGPIPE).
pub const CLOSED_PIPE: u8 = 141;

/// `print!` to stdout; a failed write ends the process (see the module docs).
macro_rules! print {
    ($($arg:tt)*) => { $crate::out::stdout(format_args!($($arg)*), false) };
}

/// `println!` to stdout; a failed write ends the process (see the module docs).
macro_rules! println {
    () => { $crate::out::stdout(format_args!(""), true) };
    ($($arg:tt)*) => { $crate::out::stdout(format_args!($($arg)*), true) };
}

#[allow(unused_macros)]
/// `eprint!` that ignores a failed write instead of panicking.
macro_rules! eprint {
    ($($arg:tt)*) => { $crate::out::stderr(format_args!($($arg)*), false) };
}

/// `eprintln!` that ignores a failed write instead of panicking.
macro_rules! eprintln {
    () => { $crate::out::stderr(format_args!(""), true) };
    ($($arg:tt)*) => { $crate::out::stderr(format_args!($($arg)*), true) };
}

/// Writes to stdout (and a newline if asked); a failed write ends the process.
pub fn stdout(args: std::fmt::Arguments<'_>, newline: bool) {
    let mut out = std::io::stdout().lock();
    let r = out.write_fmt(args).and_then(|()| {
        if newline {
            out.write_all(b"\n")
        } else {
            Ok(())
        }
    });
    if let Err(e) = r {
        fail(&e);
    }
}

/// Writes to stderr (and a newline if asked), ignoring errors.
pub fn stderr(args: std::fmt::Arguments<'_>, newline: bool) {
    let mut err = std::io::stderr().lock();
    let _ = err.write_fmt(args).and_then(|()| {
        if newline {
            err.write_all(b"\n")
        } else {
            Ok(())
        }
    });
}

/// Flushes stdout at the end of a command; a failed flush ends the process like a failed write.
pub fn flush() {
    if let Err(e) = std::io::stdout().flush() {
        fail(&e);
    }
}

fn fail(e: &std::io::Error) -> ! {
    if e.kind() == ErrorKind::BrokenPipe {
        std::process::exit(CLOSED_PIPE.into());
    }
    stderr(format_args!("error: cannot write the output: {e}"), true);
    std::process::exit(crate::exit::BAD_INPUT.into());
}
