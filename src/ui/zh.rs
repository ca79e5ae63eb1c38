//! What the window says in Chinese of the layers below it: their errors, and the Tuya
//! handshake's step results. Each such type's English is its `Display` (what the command line
//! prints); [`Zh`] gives the same message in Chinese, with the same values (idents, numbers,
//! paths) and the nested error's own Chinese. What the operating system or a parser said (a port
//! that cannot open, a RON syntax error) is quoted as it came. The window is the only reader of
//! Chinese: the layers below carry typed values and English, never a Chinese text.

use crate::capture::CaptureError;
use crate::document::{DocumentError, ErrorKind};
use crate::i18n::{Lang, Text};
use crate::link::session::tuya::StepResult;
use crate::link::{ExchangeError, LinkError};
use crate::ops::OpError;
use crate::profile::{DpLimit, FieldError};
use crate::protocol::FrameError;
use crate::protocol::tuya::VERSION_MCU;
use crate::protocol::tuya::dp::DpError;
use crate::ui::jobs::{JobError, LogError};
use crate::ui::station::ConnectError;

/// The fixed phrases of why a port or a link was lost, as the link and the system's port
/// lookup write them (`crate::link::serial`, `crate::system::vanished`, the link's worker),
/// and their Chinese; a longer phrase before one it holds.
const LOST_PORT: &[(&str, &str)] = &[
    ("port disconnected: ", "串口已断开:"),
    (
        ": no such port (not plugged in, or plugged in under another name); ",
        ":没有此串口(未插上,或以另一个名称插上);",
    ),
    (
        "no USB serial port is listed now: plug the adapter in",
        "现在没有列出任何 USB 串口:请插上适配器",
    ),
    ("the USB serial ports listed now: ", "现在列出的 USB 串口:"),
    (
        " (`botbench ports` lists every port)",
        "(`botbench ports` 列出所有串口)",
    ),
    ("port lost: ", "串口丢失:"),
    ("link lost: ", "连接丢失:"),
    ("link closed", "连接已关闭"),
    (
        " is gone: unplugged (no USB serial port is listed now); plug it in again",
        " 已不存在:已拔出(现在没有列出任何 USB 串口);请重新插上",
    ),
    (
        " is gone: unplugged, or plugged in again under another name (listed now: ",
        " 已不存在:已拔出,或以另一个名称重新插上(现在列出:",
    ),
    (
        "renamed after a replug: the same adapter (USB serial ",
        "重新插拔后改名:同一个适配器(USB 序列号 ",
    ),
    (") is now ", ")现在是 "),
    ("; connect to that port", ";请连接该串口"),
    ("taken by brltty (pid ", "被 brltty(pid "),
    (
        "), the braille display daemon, which claims CH340/CH341 adapters on Ubuntu; without a \
         braille display, remove it: sudo apt remove brltty",
        ")占用:它是盲文显示器守护程序,在 Ubuntu 上会占用 CH340/CH341 适配器;\
         没有盲文显示器时请卸载它:sudo apt remove brltty",
    ),
    (
        "the port took no byte; waited ",
        "串口未接收任何字节;已等待 ",
    ),
    (": end of file", ":读到结尾(对端已关闭)"),
    (": the port is gone", ":串口已不存在"),
    (": write", ":写入失败"),
    (" vanished", " 已消失"),
    ("unplugged", "已拔出"),
    (" — ", "——"),
];

/// Why a port or a link was lost (`why`, as the link wrote it: `/dev/ttyUSB0: I/O error —
/// /dev/ttyUSB0 is gone: unplugged …`) in Chinese: its fixed phrases ([`LOST_PORT`]) said, the
/// paths, numbers and what the operating system said left as they came. For reasons kept as
/// English text (a record's, a verdict's) and shown in 中文.
pub fn lost_port(why: &str) -> String {
    let mut zh = crate::i18n::phrases::replace(why, LOST_PORT);
    // The list of ports now listed closes the text: its parenthesis is the Chinese one.
    if zh.contains("(现在列出:") && zh.ends_with(')') {
        zh.pop();
        zh.push(')');
    }
    zh
}

/// An error as the window says it in Chinese; its English is its `Display`.
pub trait Zh: std::fmt::Display {
    /// The message in Chinese.
    fn zh(&self) -> String;

    /// The message in both languages.
    fn said(&self) -> Text {
        Text::new(self.to_string(), self.zh())
    }

    /// The message in `lang`.
    fn in_lang(&self, lang: Lang) -> String {
        match lang {
            Lang::En => self.to_string(),
            Lang::Zh => self.zh(),
        }
    }
}

impl Zh for crate::ui::station::ReadingError {
    fn zh(&self) -> String {
        match self {
            Self::Read(e) => e.zh(),
            Self::WriteFailed(e) => format!("写入失败:{};请重新读取", e.zh()),
        }
    }
}

impl Zh for crate::ui::tuning::PendingError {
    fn zh(&self) -> String {
        match self {
            Self::Value(e) | Self::Relation { error: e, .. } => e.zh(),
            Self::NotANumber { field } => format!("{field}:不是数字"),
            Self::BlockNotRead { field } => {
                format!("{field} 尚未读取:请先全部读取,以便写入完整的参数区")
            }
            Self::NotRead { command, field } => {
                format!("{command}:{field} 尚未读取;请先读取,以便写入完整的命令")
            }
        }
    }
}

impl Zh for crate::ui::stop::SendError {
    fn zh(&self) -> String {
        match self {
            Self::Refused(e) => e.zh(),
            Self::LinkDown => "未发送:链路中断".into(),
            Self::Exchange(e) => e.zh(),
        }
    }
}

impl Zh for crate::ui::inputs::InputError {
    fn zh(&self) -> String {
        match self {
            Self::Missing { field, allowed } => format!("{field}:请给出数值({allowed})"),
            Self::Value(e) => e.zh(),
        }
    }
}

impl Zh for JobError {
    fn zh(&self) -> String {
        match self {
            JobError::Op(e) => e.zh(),
            JobError::Document(e) => e.zh(),
            JobError::Incomplete {
                failed,
                total,
                what,
            } => format!("{total} 项中 {failed} 项{}", what.zh),
            JobError::CancelledAfter { done, total, what } => {
                format!("已取消:{total} {} 中已完成 {done}", unit_zh(what))
            }
            JobError::UpdateCancelled { offset, size } => {
                format!("已取消:{size} 字节中只写到偏移 {offset},MCU 中的固件不完整")
            }
            JobError::UpdateLinkLost { offset, size, why } => {
                format!(
                    "升级过程中连接丢失(已确认 {offset} / {size} 字节):{}",
                    lost_port(why)
                )
            }
            JobError::Failed(what) => format!("不合格:{}", what.zh),
            JobError::StepFailed { step, reason } => format!("在 {step} 步失败:{reason}"),
            JobError::LinkLostDuring { step, why } => {
                format!("无结论:在“{}”步骤中连接丢失:{}", step.zh, lost_port(why))
            }
            JobError::Log(e) => e.zh(),
            JobError::File { path, reason } => format!("{}:{reason}", path.display()),
            JobError::Thread(e) => format!("无法启动任务线程:{e}"),
        }
    }
}

/// The Chinese of what a batch counts (`commands`).
fn unit_zh(what: &str) -> &str {
    match what {
        "commands" => "条命令",
        "fields" => "个字段",
        "parameters" => "个参数",
        other => other,
    }
}

impl Zh for ConnectError {
    fn zh(&self) -> String {
        match self {
            ConnectError::Profile(e) => format!("设备配置无法加载:{e}"),
            ConnectError::Simulator(e) => format!("没有这个内置模拟设备:{e}"),
            ConnectError::Link(e) => e.zh(),
        }
    }
}

impl Zh for CaptureError {
    fn zh(&self) -> String {
        match self {
            CaptureError::Open { path, reason } => format!("无法打开抓包文件 {path}:{reason}"),
            CaptureError::Write(e) => format!("无法写入抓包文件:{e}"),
            CaptureError::Format(e) => format!("不是 botbench 抓包文件:{e}"),
        }
    }
}

impl Zh for LogError {
    fn zh(&self) -> String {
        format!("无法追加写入 {}:{}", self.path.display(), self.reason)
    }
}

impl Zh for OpError {
    fn zh(&self) -> String {
        match self {
            OpError::Value(e) => e.zh(),
            OpError::UnknownCommand { profile, command } => {
                format!("设备配置 {profile} 没有命令 {command}")
            }
            OpError::UnknownParam { profile, param } => {
                format!("设备配置 {profile} 没有参数 {param}")
            }
            OpError::WrongCommand { command, .. } => {
                format!("{command} 的类型不适用于此操作(未发送)")
            }
            OpError::CannotKeep {
                command,
                field,
                why,
            } => format!("{command}:无法保留设备的 {field}:{why};请给出 {field}=数值"),
            OpError::NothingGiven { what, .. } => format!("未给出{what}(未发送)"),
            OpError::OutOfRange {
                what,
                value,
                min,
                max,
                ..
            } => format!("{what} {value} 超出范围;允许 {min} 至 {max}"),
            OpError::ReadOnly { param } => format!("{param} 为只读"),
            OpError::BroadcastId => "ID 255 是广播地址,不能分配".into(),
            OpError::BroadcastAnswer { .. } => {
                "ID 255 是广播地址:所有舵机都会执行且都不应答,请给出单个舵机的 ID".into()
            }
            OpError::SameId { id } => format!("舵机 {id} 已经是 ID {id}"),
            OpError::IdInUse { id, .. } => format!("ID {id} 已在总线上应答"),
            OpError::NotAlone { answering } => {
                format!("新舵机(ID 0)只能在总线上只有它时分配 ID;正在应答的 ID:{answering:?}")
            }
            OpError::MissingValue { param, data_id } => {
                format!("参数块缺少 {param}({data_id})的值")
            }
            OpError::FollowedChange { param, .. } => {
                format!("参数块会改变 {param}:ID 与波特率请用各自的命令修改")
            }
            OpError::FactoryIdTaken { id, baud } => format!(
                "已有舵机在出厂 ID {id}、波特率 {baud} 上应答:复位后两者 ID 相同,请先给它另一个 ID"
            ),
            OpError::EmptyImage => "固件文件为空".into(),
            OpError::ImageTooLarge { size, max } => {
                format!("固件为 {size} 字节,超过设备配置允许的最大值({max} 字节)")
            }
            OpError::Document(e) => e.zh(),
            OpError::Port { baud, error } => {
                format!("无法将串口切换到 {baud} 波特:{}", error.zh())
            }
            OpError::Exchange(e) => e.zh(),
            OpError::Answer { command, error } => {
                format!("{command}:应答与设备配置不符:{}", error.zh())
            }
            OpError::NotAtNewRate { id, baud, found } => match found {
                Some(b) => {
                    format!("舵机 {id} 在 {baud} 波特下无应答;它在 {b} 波特下被找到(串口现为 {b})")
                }
                None => format!("舵机 {id} 在 {baud} 波特及其他波特率下均无应答"),
            },
            OpError::Verify(what) => format!("校验不符:{what}"),
            OpError::NotBroadcast { param } => format!(
                "{param} 不能一次写入所有舵机:它决定如何找到舵机;请用 set-id 或 set-baud 逐个设置"
            ),
            OpError::Cancelled => "已取消".into(),
            OpError::CancelledAfter {
                done,
                total,
                done_items,
                not_done,
                ..
            } => {
                let mut s = format!("已在 {total} 项中完成 {done} 项后取消");
                if !done_items.is_empty() {
                    s.push_str(&format!(";已完成:{}", done_items.join(", ")));
                }
                if !not_done.is_empty() {
                    s.push_str(&format!(";未完成:{}", not_done.join(", ")));
                }
                s
            }
        }
    }
}

impl Zh for ExchangeError {
    fn zh(&self) -> String {
        match self {
            ExchangeError::Timeout {
                command,
                attempts,
                waited_ms,
                host_late,
            } => {
                let held_up = host_late.map_or(String::new(), |late| {
                    format!("——{}", crate::link::request::held_up_said(late).zh)
                });
                format!(
                    "命令 {command} 无应答(尝试 {attempts} 次,每次等待 {waited_ms} ms){held_up}"
                )
            }
            ExchangeError::Garbled { command, error } => {
                format!("命令 {command} 的应答已损坏:{}", error.zh())
            }
            ExchangeError::Mismatch {
                expected,
                got,
                from,
            } => {
                let from = from.map_or(String::new(), |id| format!("(来自舵机 {id})"));
                format!("等待命令 {expected} 的应答,收到的是命令 {got}{from}")
            }
            ExchangeError::Unreadable { command, reason } => {
                format!("命令 {command} 的应答无法解读:{reason}")
            }
            ExchangeError::NotInProtocol { what, protocol } => {
                format!("{} 协议没有 {what}", protocol.name())
            }
            ExchangeError::Encode(e) => format!("无法发送:{e}"),
            ExchangeError::Taken { command, port, by } => format!(
                "命令 {command} 无应答:另有程序在读取 {port},字节被它取走({by});请关闭它后重试"
            ),
            ExchangeError::NotThisDevice {
                command,
                hw,
                claimed,
                profile,
            } => format!(
                "命令 {command} 未发送:设备报告的硬件为 {hw:#04x},而配置 {profile} 适用于硬件 {claimed:#04x};请选择此设备的配置"
            ),
            ExchangeError::Disconnected(e) => format!("连接丢失:{}", lost_port(e)),
            ExchangeError::Cancelled => "已取消".into(),
        }
    }
}

impl Zh for LinkError {
    fn zh(&self) -> String {
        match self {
            LinkError::Open { path, reason } => format!("无法打开 {path}:{}", lost_port(reason)),
            LinkError::Disconnected(e) => format!("串口已断开:{}", lost_port(e)),
            LinkError::Setting(e) => format!("串口拒绝此设置:{e}"),
        }
    }
}

impl Zh for FrameError {
    fn zh(&self) -> String {
        match self {
            FrameError::Checksum {
                expected, actual, ..
            } => format!("校验和错误:应为 {expected:#04x},收到 {actual:#04x}"),
            FrameError::TooLong { len, cap, .. } => {
                format!("帧长度 {len} 超过上限 {cap} 字节")
            }
            FrameError::UnknownHeader { value, .. } => format!("帧头中有未知值 {value:#04x}"),
            FrameError::Junk { len, .. } => format!("跳过 {len} 个无效字节"),
            FrameError::Truncated { have, need, .. } => match need {
                Some(n) => format!("帧不完整:{n} 字节中只有 {have}"),
                None => format!("帧不完整:只有 {have} 字节"),
            },
        }
    }
}

impl Zh for DpError {
    fn zh(&self) -> String {
        match self {
            DpError::Truncated { offset, need, have } => {
                format!("第 {offset} 字节处的数据点不完整:需要 {need} 字节,只有 {have}")
            }
            DpError::UnknownType { id, ty } => format!("数据点 {id} 的类型 {ty} 未知"),
            DpError::BadLength {
                id,
                ty,
                len,
                expected,
            } => format!("数据点 {id}(类型 {ty})长度为 {len},应为 {expected}"),
            DpError::NotUtf8 { id } => format!("数据点 {id} 的字符串不是有效的 UTF-8"),
            DpError::TooLong { id, len } => {
                format!("数据点 {id} 长 {len} 字节,超过最大值 65535")
            }
        }
    }
}

impl Zh for DpLimit {
    fn zh(&self) -> String {
        match self {
            DpLimit::OutOfRange {
                value,
                min,
                max,
                unit,
            } => format!("{value}{unit} 超出范围:设备配置允许 {min} 至 {max}{unit}"),
            DpLimit::OffStep {
                value,
                step,
                min,
                unit,
            } => format!("{value}{unit} 不在步长上:设备配置允许从 {min} 起以 {step} 为步长"),
            DpLimit::NoLabel { index, allowed } => {
                format!("枚举序号 {index} 没有标签:设备配置的标签为 {allowed}")
            }
            DpLimit::UndefinedBits { undefined, defined } => {
                format!("位 {undefined:#x} 未定义:设备配置定义的位为 {defined}")
            }
            DpLimit::TooLong { len, max } => format!("{len} 字节,超过设备配置的最大值 {max}"),
        }
    }
}

/// A Tuya data point type as Tuya's Chinese documents name it (布尔型 for bool), in `lang`.
pub fn dp_type(ty: crate::protocol::tuya::dp::DpType, lang: Lang) -> &'static str {
    use crate::protocol::tuya::dp::DpType;
    match lang {
        Lang::En => ty.name(),
        Lang::Zh => match ty {
            DpType::Raw => "透传型",
            DpType::Bool => "布尔型",
            DpType::Value => "数值型",
            DpType::String => "字符型",
            DpType::Enum => "枚举型",
            DpType::Bitmap => "故障型",
        },
    }
}

/// A data point type by its name ([`crate::protocol::tuya::dp::DpType::name`]) as
/// [`dp_type`] in Chinese; the name as given when it is none of the six.
fn dp_type_named(name: &str) -> String {
    (0..=5u8)
        .filter_map(crate::protocol::tuya::dp::DpType::from_byte)
        .find(|t| t.name() == name)
        .map_or_else(|| name.to_string(), |t| dp_type(t, Lang::Zh).to_string())
}

/// A type byte on the wire as [`dp_type`] in Chinese, or the byte when it is none of the six.
fn wire_type_zh(byte: u8) -> String {
    crate::protocol::tuya::dp::DpType::from_byte(byte).map_or_else(
        || format!("{byte:#04x}"),
        |t| dp_type(t, Lang::Zh).to_string(),
    )
}

impl Zh for crate::ops::tuya::DpMisfit {
    fn zh(&self) -> String {
        use crate::ops::tuya::DpMisfit;
        match self {
            DpMisfit::Type { wire, expected } => format!(
                "线上类型为{},设备配置为{}",
                wire_type_zh(*wire),
                dp_type(*expected, Lang::Zh)
            ),
            DpMisfit::UnknownType { wire } => {
                format!("类型字节 {wire:#04x} 不是六种数据点类型之一")
            }
            DpMisfit::Length { ty, len, expected } => format!(
                "线上为 {len} 字节的{};{}应为 {expected} 字节",
                dp_type(*ty, Lang::Zh),
                dp_type(*ty, Lang::Zh)
            ),
            DpMisfit::NotBool { byte } => {
                format!("布尔字节为 {byte:#04x}:布尔型只能是 0x00 或 0x01")
            }
            DpMisfit::NotUtf8 => "字符串不是有效的 UTF-8".into(),
            DpMisfit::Limit(l) => l.zh(),
            DpMisfit::Truncated { reason } => format!("数据不完整:{reason}"),
        }
    }
}

impl Zh for FieldError {
    fn zh(&self) -> String {
        match self {
            FieldError::OutOfRange {
                field,
                value,
                min,
                max,
                unit,
            } => format!("{field}:{value} 超出范围;允许 {min} 至 {max}{unit}"),
            FieldError::NotALabel {
                field,
                value,
                allowed,
            } => format!("{field}:'{value}' 不是可选值之一({allowed})"),
            FieldError::NotANumber {
                field,
                input,
                allowed,
            } => format!("{field}:'{input}' 不是数字;允许 {allowed}"),
            FieldError::NoValue { field, allowed } => {
                format!("{field}:未给出数值;允许 {allowed}")
            }
            FieldError::NotOnStep { field, input, step } => {
                format!("{field}:{input} 不是步长 {step} 的整数倍")
            }
            FieldError::WrongType { field, expected } => format!("{field}:应为 {expected}"),
            FieldError::WrongLength {
                field,
                expected,
                actual,
            } => format!("{field}:应为 {expected} 字节,收到 {actual}"),
            FieldError::ShortPayload { field, need, have } => {
                format!("{field}:数据提前结束:还需 {need} 字节,只剩 {have}")
            }
            FieldError::NotUtf8 { field } => format!("{field}:文本不是有效的 UTF-8"),
            FieldError::UnknownField { command, field, .. } => {
                format!("{command} 没有字段 '{field}'")
            }
            FieldError::UnknownDataPoint { name, known } => {
                format!("没有数据点 '{name}';数据点:{known}")
            }
            FieldError::Duplicate { command, field } => {
                format!("{command}:'{field}' 给出了两次;只能给一次")
            }
            FieldError::MissingField { command, field } => {
                format!("{command}:缺少字段 '{field}'")
            }
            FieldError::DataPointLimit { field, limit } => format!("{field}:{}", limit.zh()),
            FieldError::ReadOnly { field } => format!("{field} 为只读"),
            FieldError::Unknown { what, id } => format!("设备配置中没有 {what} {id}"),
            FieldError::DpType {
                field,
                expected,
                actual,
            } => format!(
                "数据点 {field}:线上类型为{},设备配置为{}",
                dp_type_named(actual),
                dp_type_named(expected)
            ),
            FieldError::Dp(e) => e.zh(),
            FieldError::LongPayload { extra } => {
                format!("布局最后一个字段之后多出 {} 字节", extra.len())
            }
            FieldError::Misfit(m) => {
                let expected = match m.expected {
                    (lo, Some(hi)) if lo == hi => format!("{lo} 字节"),
                    (lo, Some(hi)) => format!("{lo} 至 {hi} 字节"),
                    (lo, None) => format!("至少 {lo} 字节"),
                };
                format!(
                    "{} 字节的数据,布局需要 {expected}:{}",
                    m.payload.len(),
                    m.fault.zh()
                )
            }
            FieldError::Records { field, message } => format!("{field}:{message}"),
            FieldError::Relation(b) => format!(
                "{}({}){} 必须 {} {}({}){}",
                b.low_name, b.low, b.low_value, b.sign, b.high_name, b.high, b.high_value
            ),
        }
    }
}

impl Zh for DocumentError {
    fn zh(&self) -> String {
        let kind = match self.kind {
            ErrorKind::Io => "无法读写文件",
            ErrorKind::Syntax => "格式错误",
            ErrorKind::Version => "版本不符",
            ErrorKind::Profile => "不是此设备配置的文件",
            ErrorKind::Value => "数值不被设备配置接受",
        };
        let (line, col) = self.at();
        let place = if line == 0 {
            self.file.clone()
        } else {
            format!("{}:{line}:{col}", self.file)
        };
        let more = match self.problems.len() {
            1 => String::new(),
            n => format!("(共 {n} 处问题)"),
        };
        format!("{place}:{kind}{more}:{}", self.message())
    }
}

impl Zh for StepResult {
    fn zh(&self) -> String {
        match self {
            StepResult::Heartbeat {
                first_since_start,
                frame_version,
            } => {
                let answer = if *first_since_start {
                    "应答 0:MCU 启动后的第一次"
                } else {
                    "应答 1"
                };
                match frame_version {
                    Some(v) if *v == VERSION_MCU => format!("{answer};MCU 帧版本 {v:#04x}"),
                    Some(v) => {
                        format!("{answer};MCU 帧版本 {v:#04x}(协议文档为 {VERSION_MCU:#04x})")
                    }
                    None => answer.to_string(),
                }
            }
            StepResult::ProductInfo(info) => match &info.error {
                None => {
                    let pid = info.pid.as_deref().unwrap_or("?");
                    let version = info.version.as_deref().unwrap_or("?");
                    let mode = info.mode.map_or("?".to_string(), |m| m.to_string());
                    format!("PID {pid},MCU {version},配网模式 {mode}")
                }
                Some(e) => format!("不是有效的 JSON({e});按原样显示:{}", info.raw),
            },
            StepResult::WorkMode { gpio: None } => "MCU 控制 WiFi 指示灯".into(),
            StepResult::WorkMode {
                gpio: Some((led, reset)),
            } => format!("模块控制指示灯(GPIO {led},复位 GPIO {reset})"),
            StepResult::WifiStateNotNeeded => "不需要:模块控制指示灯".into(),
            StepResult::WifiStateReported { state } => format!("已上报状态 {state}"),
            StepResult::Status { total, missing } if missing.is_empty() => {
                format!("{total} 个数据点全部已上报")
            }
            StepResult::Status { total, missing } => format!(
                "{total} 个数据点中 {} 个已上报;未上报:{}",
                total - missing.len(),
                join_ids(missing)
            ),
            StepResult::Failed(e) => e.zh(),
        }
    }
}

/// Data point ids as a list: `3, 7, 12`.
fn join_ids(ids: &[u8]) -> String {
    ids.iter().map(u8::to_string).collect::<Vec<_>>().join(", ")
}

/// A value as the profile shows it ([`crate::profile::Field::display`]), its marks said in
/// `lang`: in 中文 `(raw 1779)` → `(原始值 1779)`, `!! out of range 0 to 100 %` →
/// `!! 超出范围 0 至 100 %`.
pub fn value_marks(shown: &str, lang: Lang) -> String {
    if lang == Lang::En {
        return shown.to_string();
    }
    let shown = shown.replace(" (raw ", " (原始值 ").replace("n/a ", "无 ");
    match shown.split_once("!! out of range ") {
        Some((value, range)) => format!("{value}!! 超出范围 {}", range.replacen(" to ", " 至 ", 1)),
        None => shown,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    /// The English words left in `zh`: words of three letters or more, except those that are
    /// values (paths, the program named, the command to run, the OS's own words in `os`).
    fn english_in(zh: &str, os: &str) -> Vec<String> {
        const VALUES: &[&str] = &[
            "dev", "ttyUSB", "USB", "brltty", "sudo", "apt", "remove", "Ubuntu", "pid", "pts",
            // The simulated port's device, by its kind's name.
            "window", "cleaner",
        ];
        zh.split(|c: char| !c.is_ascii_alphabetic())
            .filter(|w| w.len() >= 3 && !VALUES.contains(w) && !os.contains(w))
            .map(str::to_string)
            .collect()
    }

    /// Every reason a port is lost for, as the link writes it, is said in 中文 but for its
    /// values: a NO VERDICT banner, a station's reason or a record's row keeps the reason as
    /// English text (before: the lost port's reason under a Chinese banner stayed English).
    #[test]
    fn every_reason_a_port_is_lost_for_is_said_in_chinese() {
        let os = "Input/output error (os error 5)";
        let mut reasons: Vec<String> = crate::system::every_vanish_cause("/dev/ttyUSB0")
            .into_iter()
            .map(|cause| format!("port disconnected: /dev/ttyUSB0: {os} — {cause}"))
            .collect();
        assert_eq!(reasons.len(), 5, "{reasons:#?}");
        reasons.extend(
            [
                "port disconnected: /dev/ttyUSB0: end of file",
                "port disconnected: /dev/ttyUSB0: write",
                "port disconnected: /dev/ttyUSB0: the port is gone",
                "port disconnected: /dev/ttyUSB0: the port took no byte; waited 500 ms",
                "port lost: port disconnected: /dev/pts/3: end of file",
                "link lost: link closed",
                "port disconnected: window-cleaner vanished",
                "unplugged",
            ]
            .map(String::from),
        );
        for en in &reasons {
            let zh = lost_port(en);
            let left = english_in(&zh, os);
            assert!(left.is_empty(), "{en:?} → {zh:?}: {left:?}");
        }
        assert_eq!(
            lost_port(&reasons[3]),
            "串口已断开:/dev/ttyUSB0: Input/output error (os error 5)——/dev/ttyUSB0 已不存在:\
             已拔出,或以另一个名称重新插上(现在列出:/dev/ttyUSB1, /dev/ttyUSB2)"
        );
    }

    /// A port that is not there at all says so in 中文 too (the OS's words quoted).
    #[test]
    fn a_port_that_is_not_there_is_said_in_chinese() {
        let os = "No such file or directory (os error 2)";
        let e = LinkError::Open {
            path: "/dev/ttyUSB7".into(),
            reason: crate::system::missing_port("/dev/ttyUSB7", os),
        };
        let zh = e.zh();
        assert!(zh.contains("没有此串口(未插上,或以另一个名称插上)"), "{zh}");
        // The command to type stays as typed.
        let left = english_in(&zh.replace("`botbench ports`", ""), os);
        assert!(left.is_empty(), "{zh:?}: {left:?}");
    }

    /// A timeout on a held-up computer says so in 中文 too, with the figure, and no English.
    #[test]
    fn a_timeout_on_a_held_up_computer_says_so_in_chinese() {
        let timeout = |host_late| ExchangeError::Timeout {
            command: 3.into(),
            attempts: 2,
            waited_ms: 25,
            host_late,
        };
        let late = timeout(Some(Duration::from_millis(31))).zh();
        assert!(
            late.contains("这台电脑在应答截止时间后被拖住了 31 ms")
                && late.contains("电脑负载过高")
                && late.contains("请关闭其他程序后重试"),
            "{late}"
        );
        assert!(
            !late.contains("held up") && !late.contains("loaded"),
            "{late}"
        );
        let on_time = timeout(None).zh();
        assert!(!on_time.contains("拖住"), "{on_time}");
    }
}
