//! What HNAV knows of one robot outside it: when it was last heard, its wheels' angles, its
//! ground truth, and what its `cmd_vel` last said; and the rules that make a silent robot
//! `down` and a stale command a stop.

use std::time::{Duration, Instant};

use hnav_runtime::msg::Pose;

use super::wheels::OdomWheels;

/// One robot outside HNAV; the default is one never heard, never commanded, never sent a
/// stop (so the first stop a rule asks for goes out).
#[derive(Debug, Clone, Default)]
pub struct OutsideRobot {
    /// When its odometry source was last heard from (`None`: never).
    pub heard: Option<Instant>,
    /// Down: not heard for the silence bound (since the start, for one never heard).
    pub down: bool,
    /// Its wheels' cumulative angles, rad (left, right).
    pub angles: (f64, f64),
    /// The odom source's state, for `odometry = "odom"`.
    pub odom: OdomWheels,
    /// Its last ground truth from outside, in HNAV's frame.
    pub truth: Option<Pose>,
    /// When its agent's last wheel command came (`None`: none yet).
    pub commanded: Option<Instant>,
    /// Whether the last `cmd_vel` sent was a stop (so a stop is sent once, not every period).
    pub stopped: bool,
    /// The agent is down or lost (the supervisor's word): the robot is held.
    pub agent_down: bool,
}

/// What changed about a robot's liveness at a check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Liveness {
    /// As before.
    Same,
    /// It just went silent past the bound.
    WentDown,
    /// It was down and is heard again.
    Back,
}

impl OutsideRobot {
    /// Takes a message from its odometry source at `now`.
    pub fn hear(&mut self, now: Instant) {
        self.heard = Some(now);
    }

    /// Applies the silence rule at `now`: down once not heard for `silence` (counted from
    /// `start` for a robot never heard).
    pub fn check(&mut self, now: Instant, start: Instant, silence: Duration) -> Liveness {
        let since = self.heard.unwrap_or(start);
        let silent = now.saturating_duration_since(since) > silence;
        match (self.down, silent) {
            (false, true) => {
                self.down = true;
                Liveness::WentDown
            }
            (true, false) => {
                self.down = false;
                Liveness::Back
            }
            _ => Liveness::Same,
        }
    }

    /// Whether its wheels must be stopped at `now`: it is down, its agent is, or the
    /// agent's last command is older than the motor watchdog's `watchdog` (as `hnav-sim`
    /// brakes a stale command).
    pub fn must_stop(&self, now: Instant, watchdog: Duration) -> bool {
        self.down
            || self.agent_down
            || self
                .commanded
                .is_some_and(|c| now.saturating_duration_since(c) > watchdog)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn silent_past_the_bound_is_down_and_heard_again_is_back() {
        let t0 = Instant::now();
        let s = Duration::from_millis(100);
        let mut r = OutsideRobot::default();
        assert_eq!(
            r.check(t0 + Duration::from_millis(50), t0, s),
            Liveness::Same
        );
        // Never heard: down once the bound has passed since the start.
        assert_eq!(
            r.check(t0 + Duration::from_millis(150), t0, s),
            Liveness::WentDown
        );
        assert!(r.down);
        assert_eq!(
            r.check(t0 + Duration::from_millis(160), t0, s),
            Liveness::Same
        );
        r.hear(t0 + Duration::from_millis(170));
        assert_eq!(
            r.check(t0 + Duration::from_millis(180), t0, s),
            Liveness::Back
        );
        assert_eq!(
            r.check(t0 + Duration::from_millis(300), t0, s),
            Liveness::WentDown
        );
    }

    #[test]
    fn a_stale_command_or_a_down_robot_or_agent_stops_the_wheels() {
        let t0 = Instant::now();
        let w = Duration::from_millis(100);
        let mut r = OutsideRobot::default();
        assert!(!r.must_stop(t0, w), "no command yet: nothing to stop");
        r.commanded = Some(t0);
        assert!(!r.must_stop(t0 + Duration::from_millis(90), w));
        assert!(r.must_stop(t0 + Duration::from_millis(110), w));
        r.commanded = Some(t0 + Duration::from_millis(110));
        r.agent_down = true;
        assert!(r.must_stop(t0 + Duration::from_millis(120), w));
        r.agent_down = false;
        r.down = true;
        assert!(r.must_stop(t0 + Duration::from_millis(120), w));
    }
}
