// The enumerations and small structures of Ixxat.Vci3.Bal.Can. The manual names the members it
// uses and gives no values (chapter 5 is missing): the values are those of IXXAT's cantype.h
// (VCI 3), so that a number a program logs means what it means on the vendor's adapter.
using System;

namespace Ixxat.Vci3.Bal.Can
{
  [Flags]
  public enum CanOperatingModes : byte
  {
    Undefined = 0x00,
    Standard = 0x01,  // 11-bit identifiers
    Extended = 0x02,  // 29-bit identifiers
    ErrFrame = 0x04,  // error frames reported as CanMsgFrameType.Error messages
    ListOnly = 0x08,  // listen only: no acknowledgement, no transmission
    LowSpeed = 0x10,  // low-speed transceiver
  }

  public enum CanMsgFrameType : byte
  {
    Data = 0, Info = 1, Error = 2, Status = 3, Wakeup = 4, TimeOverrun = 5, TimeReset = 6,
  }

  // The first data byte of a CanMsgFrameType.Info message.
  public enum CanMsgInfoValue : byte { Start = 1, Stop = 2, Reset = 3 }

  // The first data byte of a CanMsgFrameType.Error message (VCI 3 numbering).
  public enum CanMsgError : byte { Stuff = 1, Form = 2, Acknowledge = 3, Bit = 4, Crc = 6, Other = 7 }

  // Selects the 11-bit or the 29-bit filter of ICanControl.
  public enum CanFilter : byte { Std = 1, Ext = 2 }

  public enum CanAccCode : uint { All = 0x00000000, None = 0x80000000 }
  public enum CanAccMask : uint { All = 0x00000000, None = 0xFFFFFFFF }

  // Why a received message passed the filter (CanMessage.AcceptReason).
  public enum CanAcceptReason : byte { Reject = 0, AcceptanceFilter = 1, FilterList = 2, Always = 0xFF }

  public enum CanCyclicTXIncMode : byte { NoInc = 0, IncId = 1, Inc8 = 2, Inc16 = 3 }

  public enum CanCyclicTXStatus : byte { Empty = 0, Busy = 1, Done = 2 }

  public enum CanCtrlType : byte
  {
    Unknown = 0, Intel82527 = 1, Intel82C200 = 2, Intel81C90 = 3, Intel81C92 = 4, Sja1000 = 5,
    Infineon82C900 = 6, MotorolaToucan = 7, FreescaleMscan = 8, FreescaleFlexcan = 9, IfiCan = 10,
    BoschCcan = 11, StBxcan = 12, IfiCanFd = 13, BoschMcan = 14,
  }

  public enum CanBusCoupling : ushort { Undefined = 0, LowSpeed = 1, HighSpeed = 2 }

  // The state of a CAN line (ICanSocket.LineStatus).
  public struct CanLineStatus
  {
    internal CanOperatingModes mode;
    internal CanBitrate bitrate;
    internal byte busLoad;
    internal uint status;

    public CanOperatingModes OperatingMode { get { return mode; } }
    public CanBitrate Bitrate { get { return bitrate; } }
    public byte BusLoad { get { return busLoad; } }
    public bool IsTransmitPending { get { return (status & 0x01) != 0; } }
    public bool HasDataOverrun { get { return (status & 0x02) != 0; } }
    public bool HasErrorWarningLevel { get { return (status & 0x04) != 0; } }
    public bool IsBusOff { get { return (status & 0x08) != 0; } }
    public bool IsInInitMode { get { return (status & 0x10) != 0; } }
    public uint Status { get { return status; } }

    public override string ToString()
    {
      return string.Format("{0} {1} busload {2} % init={3} busoff={4} warning={5} overrun={6}",
                           mode, bitrate, busLoad, IsInInitMode, IsBusOff, HasErrorWarningLevel,
                           HasDataOverrun);
    }
  }

  // The state of a channel (ICanChannel.ChannelStatus).
  public struct CanChannelStatus
  {
    internal CanLineStatus line;
    internal bool activated, overrun;
    internal byte rxLoad, txLoad;

    public CanLineStatus LineStatus { get { return line; } }
    public bool IsActivated { get { return activated; } }
    public bool HasFifoOverrun { get { return overrun; } }
    public byte ReceiveFifoLoad { get { return rxLoad; } }
    public byte TransmitFifoLoad { get { return txLoad; } }
  }
}
